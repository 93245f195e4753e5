"""All-or-nothing changes to the knowledge, and what each one changed.

Why it is built this way: instances, facts and fluent values live in journaled
tables that log what each change touches. A failed change is undone from that log,
and what changed is computed from it (net of what came back), so a subscriber gets
exactly one :class:`KnowledgeChange` per change (or per transaction) saying
precisely what moved, however the change was made, at a cost in the size of the
change rather than of the knowledge. One re-entrant lock: adapters and the
executor call in from other threads.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Self

from plansys_bridge.knowledge.journal import JournaledTable
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import Atom, Condition

__all__ = [
    "EMPTY_SET",
    "AppliedEffect",
    "ChangeTracker",
    "KnowledgeChange",
    "applied_effect",
    "net_change",
]

log = logging.getLogger("plansys_bridge.knowledge.problem_expert")

EMPTY_SET: frozenset[Any] = frozenset()
"""The empty set a notice without such changes holds (one, shared)."""


@dataclass(frozen=True)
class KnowledgeChange:
    """What one change (or one transaction) did to the knowledge."""

    version: int
    reason: str
    added_instances: Mapping[str, str] = field(default_factory=dict)
    removed_instances: Mapping[str, str] = field(default_factory=dict)
    added_facts: frozenset[Atom] = frozenset()
    removed_facts: frozenset[Atom] = frozenset()
    changed_fluents: Mapping[FluentKey, float] = field(default_factory=dict)
    removed_fluents: frozenset[FluentKey] = frozenset()
    goal_changed: bool = False
    goal: Condition | None = None
    state: State | None = field(default=None, compare=False, repr=False)
    """The snapshot right after the change (read it without taking the lock)."""

    @classmethod
    def _made(cls, **fields: Any) -> KnowledgeChange:
        """A change with every field given, its instance dict filled at once.

        Why: one is made per change, and the frozen dataclass's ``__init__`` sets
        its eleven fields one ``object.__setattr__`` at a time (about three times
        the cost). Equality, ``repr`` and immutability are the dataclass's own."""
        change = object.__new__(cls)
        change.__dict__.update(fields)
        return change


class AppliedEffect(NamedTuple):
    """What applying one effect changed, net, so that it can be undone: the facts it
    made true, the facts it made false and each fluent it changed with its old value
    (None: it had none) and its new one."""

    added: tuple[Atom, ...]
    deleted: tuple[Atom, ...]
    fluents: tuple[tuple[FluentKey, float | None, float], ...]


def applied_effect(
    state: State, adds: list[Atom], deletes: list[Atom], updates: Mapping[FluentKey, float]
) -> AppliedEffect:
    """What applying ``adds``, ``deletes`` and ``updates`` to ``state`` changes, net:
    a fact deleted and added again stays, a fluent set to its value is unchanged."""
    add_set = set(adds)
    return AppliedEffect(
        tuple(dict.fromkeys([a for a in adds if a not in state])),
        tuple(dict.fromkeys([d for d in deletes if d not in add_set and d in state])),
        tuple([(k, state.value(*k), v) for k, v in updates.items() if state.value(*k) != v]),
    )


def net_change(
    removed: dict[Atom, None], added: dict[Atom, None]
) -> tuple[dict[Atom, None], dict[Atom, None]]:
    """What went and what came, net: a fact deleted and added again was there
    before and after, so it is in neither."""
    if removed and added:
        again = removed.keys() & added.keys()
        if again:
            removed = {k: None for k in removed if k not in again}
            added = {k: None for k in added if k not in again}
    return removed, added


class _Mark(NamedTuple):
    """Where a change started: log positions of the tables, the goal and the state.

    A named tuple: one is made per change, and a frozen dataclass costs several
    times as much to build."""

    instances: int
    facts: int
    fluents: int
    goal: Condition | None
    state: State


class ChangeTracker:
    """The tables, goal and state of the knowledge, changed only inside ``_change``."""

    def __init__(self, constants: Mapping[str, str]) -> None:
        self._lock = threading.RLock()
        self._instances: JournaledTable[str, str] = JournaledTable()
        self._facts: JournaledTable[Atom, None] = JournaledTable()
        self._fluents: JournaledTable[FluentKey, float] = JournaledTable()
        self._goal: Condition | None = None
        self._state = State(objects=dict(constants))
        self._published = self._state
        """The state as the last finished change left it, read without the lock by
        :meth:`ProblemExpert.state` while no change is under way (see there)."""
        self._subscribers: list[Callable[[KnowledgeChange], None]] = []
        self._depth = 0
        self.version = 0

    def _mark(self) -> _Mark:
        # tuple.__new__ directly: the named tuple's own __new__ is a Python call.
        return tuple.__new__(
            _Mark,
            (
                self._instances.mark(),
                self._facts.mark(),
                self._fluents.mark(),
                self._goal,
                self._state,
            ),
        )

    def _undo(self, mark: _Mark) -> None:
        self._instances.undo(mark.instances)
        self._facts.undo(mark.facts)
        self._fluents.undo(mark.fluents)
        self._goal = mark.goal
        self._state = mark.state

    def _change(self, reason: str, *, steps: bool = False) -> _Change:
        """Run a change all-or-nothing; notify once when the outermost block ends.

        Single operations validate everything before they touch anything, so inside
        a transaction they need no undo point of their own; ``steps=True`` marks one
        that mutates as it goes (a whole problem), which is then undone on its own
        when it fails, even if the surrounding transaction carries on.
        """
        return _Change(self, reason, steps)

    @contextmanager
    def transaction(self) -> Iterator[Self]:
        """Several changes as one: all applied or none, one notification."""
        with self._change("transaction", steps=True):
            yield self

    def _change_since(self, start: _Mark, reason: str) -> KnowledgeChange | None:
        """What the tables' logs say moved since ``start``; None when nothing did."""
        added, removed = self._facts.changes_since(start.facts)
        changed_fluents, fluents_before = self._fluents.changes_since(start.fluents)
        removed_fluents = (
            frozenset([k for k in fluents_before if k not in self._fluents])
            if fluents_before
            else EMPTY_SET
        )
        added_instances, removed_instances = self._instances.changes_since(start.instances)
        goal_changed = start.goal is not self._goal and start.goal != self._goal
        if not (
            added
            or removed
            or changed_fluents
            or removed_fluents
            or added_instances
            or removed_instances
            or goal_changed
        ):
            return None
        self.version += 1
        return KnowledgeChange._made(
            version=self.version,
            reason=reason,
            added_instances=added_instances,
            removed_instances=removed_instances,
            added_facts=frozenset(added) if added else EMPTY_SET,
            removed_facts=frozenset(removed) if removed else EMPTY_SET,
            changed_fluents=changed_fluents,
            removed_fluents=removed_fluents,
            goal_changed=goal_changed,
            goal=self._goal,
            state=self._state,
        )

    def _swap_facts(
        self, deletes: list[Atom], adds: list[Atom]
    ) -> tuple[State, AppliedEffect, frozenset[Atom], frozenset[Atom]]:
        """Delete then add facts (admitted already) as one change of its own, outside
        any transaction (the lock held), and say what changed, net, in the effect's
        order: ``(state, answer, added facts, removed facts)``, the state published,
        the notice left to the caller (:meth:`EffectApplier.apply`).

        Why: the executor applies two effects per action, and this is what the ones
        not in the usual case do (see :class:`FactChange`). The tables and state are
        those the same change makes inside :meth:`_change`, but what moved is what
        the table's writes report instead of a scan of three logs afterwards. The
        notice's sets are built from dicts in the order the scan finds them, as the
        scan does (a frozenset built from a dict is sized for it at once, so its
        iteration order differs from one built from a list).
        """
        state = self._state.with_facts(deletes, adds)  # touches nothing
        removed, added = net_change(*self._facts.swap(deletes, adds, None))  # all or nothing
        self._state = self._published = state
        return (
            state,
            tuple.__new__(AppliedEffect, (tuple(added), tuple(removed), ())),
            frozenset(added) if added else EMPTY_SET,
            frozenset(removed) if removed else EMPTY_SET,
        )

    def _notify(self, change: KnowledgeChange) -> None:
        for callback in list(self._subscribers):
            try:
                callback(change)
            except Exception:  # a broken subscriber must not break the knowledge
                log.exception("knowledge subscriber %r failed", callback)

    def subscribe(self, callback: Callable[[KnowledgeChange], None]) -> Callable[[], None]:
        """Call ``callback`` after every change; returns a function that unsubscribes."""
        with self._lock:
            self._subscribers.append(callback)

        def unsubscribe() -> None:
            with self._lock:
                if callback in self._subscribers:
                    self._subscribers.remove(callback)

        return unsubscribe


class _Change:
    """One ``with tracker._change(reason)`` block (see :meth:`ChangeTracker._change`).

    A class rather than a generator context manager: every change goes through
    one, and contextlib's wrapper costs several calls more each time."""

    __slots__ = ("_outer", "_reason", "_start", "_steps", "_tracker")

    def __init__(self, tracker: ChangeTracker, reason: str, steps: bool) -> None:
        self._tracker = tracker
        self._reason = reason
        self._steps = steps
        self._start: _Mark | None = None
        self._outer = False

    def __enter__(self) -> None:
        tracker = self._tracker
        tracker._lock.acquire()
        try:
            if not tracker._depth:
                self._start = tracker._mark()
                self._outer = True
                tracker._depth = 1
            elif self._steps:
                self._start = tracker._mark()
        except BaseException:
            tracker._lock.release()
            raise

    def __exit__(self, exc_type: type[BaseException] | None, *_exc: object) -> None:
        tracker = self._tracker
        start = self._start
        try:
            if exc_type is not None:
                if start is not None:
                    try:
                        tracker._undo(start)
                    finally:
                        if self._outer:
                            tracker._published = tracker._state
                            tracker._depth = 0
                return
            if not self._outer or start is None:
                return
            tracker._published = tracker._state  # before _depth: see ProblemExpert.state
            tracker._depth = 0
            try:
                change = tracker._change_since(start, self._reason)
            finally:
                for table in (tracker._instances, tracker._facts, tracker._fluents):
                    table.forget_log()
            if change is not None:
                tracker._notify(change)
        finally:
            tracker._lock.release()
