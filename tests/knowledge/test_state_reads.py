"""``ProblemExpert.state()`` reads the last finished snapshot without the lock while
no change is under way; during one, its own thread sees it as it goes and any other
thread never sees it half-made."""

from __future__ import annotations

import threading

from plansys_bridge.knowledge.problem_expert import KnowledgeChange, ProblemExpert
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import AddEffect, AndEffect, Atom, DeleteEffect


def _robot(simple: ProblemExpert) -> None:
    simple.add_instance("r2d2", "robot")
    for room in ("kitchen", "bedroom", "hall"):
        simple.add_instance(room, "room")


def test_another_thread_never_sees_a_transaction_half_made(simple: ProblemExpert) -> None:
    _robot(simple)
    before = simple.state()
    seen: list[State] = []
    asking = threading.Event()

    def reader() -> None:
        asking.set()
        seen.append(simple.state())

    thread = threading.Thread(target=reader)
    with simple.transaction():
        simple.add_predicate(Atom("robot_at", ("r2d2", "kitchen")))
        half = simple.state()  # its own thread sees the change as it goes
        thread.start()
        asking.wait()
        simple.add_predicate(Atom("robot_at", ("r2d2", "bedroom")))
    thread.join()
    after = simple.state()
    assert half is not before and half is not after
    assert half.tuples("robot_at") == {("r2d2", "kitchen")}
    assert seen[0] is after  # it waited for the transaction to end
    assert after.tuples("robot_at") == {("r2d2", "kitchen"), ("r2d2", "bedroom")}


def test_a_failed_change_leaves_the_snapshot_read_before(simple: ProblemExpert) -> None:
    _robot(simple)
    before = simple.state()
    try:
        with simple.transaction():
            simple.add_predicate(Atom("robot_at", ("r2d2", "kitchen")))
            raise RuntimeError("stop")
    except RuntimeError:
        pass
    assert simple.state() is before


def test_every_notice_sees_its_own_snapshot(simple: ProblemExpert) -> None:
    """Read from a subscriber, the state is the notice's (both ways of changing)."""
    _robot(simple)
    pairs: list[tuple[State | None, State]] = []

    def check(change: KnowledgeChange) -> None:
        pairs.append((change.state, simple.state()))

    simple.subscribe(check)
    simple.add_predicate(Atom("robot_at", ("r2d2", "kitchen")))
    move = AndEffect(
        (
            DeleteEffect(Atom("robot_at", ("r2d2", "kitchen"))),
            AddEffect(Atom("robot_at", ("r2d2", "hall"))),
        )
    )
    simple.apply(move)  # the short way
    with simple.transaction():
        simple.add_instance("c3po", "robot")
        simple.add_predicate(Atom("robot_at", ("c3po", "hall")))
    assert len(pairs) == 3 and all(noticed is read for noticed, read in pairs)
    assert simple.state() is pairs[-1][1]
    assert simple.state().tuples("robot_at") == {("r2d2", "hall"), ("c3po", "hall")}
