"""Applying an effect of facts outside a transaction takes a short way (a
prepared change, ``EffectApplier.apply``, or else ``ChangeTracker._swap_facts``);
it must leave the same knowledge, notices, versions and errors as the general way
(the same effect applied in a transaction, whose notice comes from scanning the
tables' logs)."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.changes import ChangeTracker, KnowledgeChange
from plansys_bridge.knowledge.journal import JournaledTable
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import (
    AddEffect,
    AndEffect,
    Atom,
    DeleteEffect,
    FluentRef,
    Number,
    NumericEffect,
)
from plansys_bridge.pddl.parser import parse_domain

DOMAIN = parse_domain(
    """(define (domain d) (:requirements :typing :fluents)
      (:types thing)
      (:predicates (p ?x - thing) (q ?x ?y - thing))
      (:functions (level ?x - thing)))""",
    "<d>",
)
OBJECTS = ("a", "b", "c")
ATOMS = [Atom("p", (x,)) for x in OBJECTS] + [Atom("q", (x, y)) for x in OBJECTS for y in "ab"]


def _knowledge(initial: list[Atom]) -> tuple[ProblemExpert, list[KnowledgeChange]]:
    k = ProblemExpert(DOMAIN)
    for name in OBJECTS:
        k.add_instance(name, "thing")
    for atom in initial:
        k.add_predicate(atom)
    k.set_function("(= (level a) 1)")
    seen: list[KnowledgeChange] = []
    k.subscribe(seen.append)
    return k, seen


def _observed(k: ProblemExpert, seen: list[KnowledgeChange]) -> tuple[object, ...]:
    notices = [
        (
            dataclasses.replace(c, reason="-"),
            list(c.added_facts),  # iteration order too: subscribers may publish it
            list(c.removed_facts),
            c.state,
        )
        for c in seen
    ]
    return k.get_predicates(), k.state(), k.version, k.get_functions(), notices


_EFFECTS = st.lists(st.tuples(st.booleans(), st.sampled_from(ATOMS)), max_size=8).map(
    lambda parts: AndEffect(tuple(AddEffect(a) if add else DeleteEffect(a) for add, a in parts))
)


_LEVELS = st.lists(
    st.builds(
        lambda op, x, v: NumericEffect(op, FluentRef("level", (x,)), Number(v)),
        st.sampled_from(["assign", "increase"]),
        st.just("a"),  # the one with a value (an increase of none fails either way)
        st.sampled_from([0.0, 1.0, 2.0]),
    ),
    max_size=2,
)


@settings(max_examples=150, deadline=None)
@given(
    initial=st.lists(st.sampled_from(ATOMS), unique=True),
    effects=st.lists(_EFFECTS, max_size=3),
    levels=_LEVELS,
)
def test_the_short_way_leaves_what_the_general_way_leaves(
    initial: list[Atom], effects: list[AndEffect], levels: list[NumericEffect]
) -> None:
    """The knowledge, the notices and what apply() says it changed, which is also
    what the effect's changes come to on the snapshot before (worked out here from
    the evaluator's answer, as sets)."""
    short, short_seen = _knowledge(initial)
    general, general_seen = _knowledge(initial)
    for i, effect in enumerate(effects):
        if i == 1:  # fluents too (then the general way both sides)
            effect = AndEffect((*effect.effects, *levels))
        before = short.state()
        adds, deletes, updates = short.evaluator.changes(effect, before)
        added = {a for a in adds if a not in before}
        deleted = {d for d in deletes if d not in set(adds) and d in before}
        fluents = tuple(
            (k, before.value(*k), v) for k, v in updates.items() if before.value(*k) != v
        )
        applied = short.apply(effect)
        with general.transaction():
            assert general.apply(effect) == applied
        assert set(applied.added) == added and len(applied.added) == len(added)
        assert set(applied.deleted) == deleted
        assert len(applied.deleted) == len(deleted) and applied.fluents == fluents
        assert short.state().facts == (before.facts - set(applied.deleted)) | set(applied.added)
    assert _observed(short, short_seen) == _observed(general, general_seen)


def test_an_effect_of_facts_takes_the_short_way(monkeypatch: pytest.MonkeyPatch) -> None:
    """Guards the comparison above: outside a transaction the logs are not scanned."""
    k, seen = _knowledge([Atom("p", ("a",))])
    scans: list[str] = []
    original = ChangeTracker._change_since

    def counted(self: ChangeTracker, start: object, reason: str) -> KnowledgeChange | None:
        scans.append(reason)
        return original(self, start, reason)  # type: ignore[arg-type]

    monkeypatch.setattr(ChangeTracker, "_change_since", counted)
    k.apply(AndEffect((DeleteEffect(Atom("p", ("a",))), AddEffect(Atom("p", ("b",))))))
    assert scans == [] and [c.reason for c in seen] == ["apply"]
    assert seen[0].removed_facts == {Atom("p", ("a",))}
    assert seen[0].added_facts == {Atom("p", ("b",))}


def test_numeric_effects_go_the_general_way() -> None:
    k, seen = _knowledge([])
    k.apply(
        AndEffect(
            (
                AddEffect(Atom("p", ("a",))),
                NumericEffect("increase", FluentRef("level", ("a",)), Number(2.0)),
            )
        )
    )
    assert k.get_function("level", ("a",)) == 3.0
    assert [(c.reason, dict(c.changed_fluents), set(c.added_facts)) for c in seen] == [
        ("apply", {("level", ("a",)): 3.0}, {Atom("p", ("a",))})
    ]


def test_a_bad_effect_changes_nothing_either_way() -> None:
    bad = AndEffect((DeleteEffect(Atom("p", ("a",))), AddEffect(Atom("p", ("zed",)))))
    for in_transaction in (False, True):
        k, seen = _knowledge([Atom("p", ("a",))])
        before = _observed(k, seen)
        with pytest.raises(KnowledgeError, match=r"predicate \(p zed\): unknown object 'zed'"):
            if in_transaction:
                with k.transaction():
                    k.apply(bad)
            else:
                k.apply(bad)
        assert _observed(k, seen) == before


class _BreaksHalfWay(tuple[Atom, ...]):
    """Keys whose iteration fails after the first one (the table has checked them
    and is changing itself)."""

    def __iter__(self) -> Iterator[Atom]:
        for i, key in enumerate(tuple.__iter__(self)):
            if i == 1:
                raise RuntimeError("out of memory")
            yield key


@pytest.mark.parametrize("usual", [True, False])
def test_a_failure_half_way_is_undone(monkeypatch: pytest.MonkeyPatch, usual: bool) -> None:
    """The usual case (the prepared change) fails half way through the fact table,
    the other (the effect adds a fact that is there) in the new snapshot."""
    k, seen = _knowledge([Atom("p", ("a",)), Atom("p", ("b",)), Atom("p", ("c",))])
    before = _observed(k, seen)
    state = k.state()
    if usual:
        effect = AndEffect(
            (
                DeleteEffect(Atom("p", ("a",))),
                AddEffect(Atom("q", ("a", "b"))),
                AddEffect(Atom("q", ("b", "b"))),
            )
        )
        exchange = JournaledTable.exchange

        def broken(self: JournaledTable[Any, Any], gone: Any, came: Any, *rest: Any) -> bool:
            return exchange(self, gone, _BreaksHalfWay(came), *rest)

        monkeypatch.setattr(JournaledTable, "exchange", broken)
    else:
        effect = AndEffect((DeleteEffect(Atom("p", ("a",))), AddEffect(Atom("p", ("b",)))))

        def broken_state(self: State, *args: object, **kwargs: object) -> State:
            raise RuntimeError("out of memory")

        monkeypatch.setattr(State, "with_facts", broken_state)
    with pytest.raises(RuntimeError, match="out of memory"):
        k.apply(effect)
    monkeypatch.undo()
    assert _observed(k, seen) == before and k.state() is state
    k.apply(AndEffect((DeleteEffect(Atom("p", ("b",))),)))
    assert k.get_predicates() == [Atom("p", ("a",)), Atom("p", ("c",))]
    assert [c.version for c in seen] == [k.version]
    k.apply(effect)  # and the same effect, applied again, works
    assert k.state().facts == {Atom(*f) for f in [("p", ("c",)), *_ADDED[usual]]}


_ADDED = {True: [("q", ("a", "b")), ("q", ("b", "b"))], False: [("p", ("b",))]}


def test_a_notice_made_at_once_equals_one_made_field_by_field() -> None:
    fields: dict[str, Any] = {
        "version": 3,
        "reason": "apply",
        "added_instances": {"a": "thing"},
        "removed_instances": {},
        "added_facts": frozenset({Atom("p", ("a",))}),
        "removed_facts": frozenset(),
        "changed_fluents": {("level", ("a",)): 2.0},
        "removed_fluents": frozenset(),
        "goal_changed": False,
        "goal": None,
        "state": State(),
    }
    assert set(fields) == {f.name for f in dataclasses.fields(KnowledgeChange)}
    made = KnowledgeChange._made(**fields)
    assert made == KnowledgeChange(**fields) and repr(made) == repr(KnowledgeChange(**fields))
    with pytest.raises(dataclasses.FrozenInstanceError):
        made.version = 4  # type: ignore[misc]


# ------------------------------------------------ effects remembered per object

_POOL = [
    AndEffect((DeleteEffect(Atom("p", ("a",))), AddEffect(Atom("p", ("c",))))),
    AndEffect((DeleteEffect(Atom("p", ("c",))), AddEffect(Atom("q", ("c", "a"))))),
    AndEffect((AddEffect(Atom("p", ("a",))), DeleteEffect(Atom("q", ("c", "a"))))),
    AddEffect(Atom("q", ("b", "b"))),
    DeleteEffect(Atom("q", ("b", "b"))),
]
"""Effect objects applied again and again (a plan's ground actions), some naming c."""

_OPS = st.lists(
    st.one_of(
        st.tuples(st.just("apply"), st.integers(0, len(_POOL) - 1)),
        st.tuples(st.sampled_from(["add", "remove"]), st.just(0)),
    ),
    max_size=12,
)


def _run(k: ProblemExpert, ops: list[tuple[str, int]], general: bool) -> list[str]:
    """Apply ``ops`` (an effect of the pool, or c added or removed); the outcome of each."""
    outcomes = []
    for op, i in ops:
        try:
            if op == "add":
                outcomes.append(str(k.add_instance("c", "thing")))
            elif op == "remove":
                outcomes.append(str(k.remove_instance("c")))
            elif general:
                with k.transaction():
                    k.apply(_POOL[i])
                outcomes.append("applied")
            else:
                k.apply(_POOL[i])
                outcomes.append("applied")
        except KnowledgeError as exc:
            outcomes.append(str(exc))
    return outcomes


@settings(max_examples=150, deadline=None)
@given(initial=st.lists(st.sampled_from(ATOMS), unique=True), ops=_OPS)
def test_remembered_effects_leave_what_the_general_way_leaves(
    initial: list[Atom], ops: list[tuple[str, int]]
) -> None:
    """The same effect objects applied again, with c coming and going in between
    (so a remembered effect naming c must be checked again)."""
    short, short_seen = _knowledge(initial)
    general, general_seen = _knowledge(initial)
    assert _run(short, ops, False) == _run(general, ops, True)
    assert _observed(short, short_seen) == _observed(general, general_seen)


def test_an_effect_applied_again_is_not_checked_again(monkeypatch: pytest.MonkeyPatch) -> None:
    """Guards the comparison above: the remembered way is taken, and left when the
    objects change."""
    k, seen = _knowledge([Atom("p", ("a",))])
    checked: list[int] = []
    facts = k._admit.facts

    def counted(atoms: Any, version: int) -> list[Atom]:
        checked.append(1)
        return facts(atoms, version)

    monkeypatch.setattr(k._admit, "facts", counted)
    there, back = _POOL[0], _POOL[2]
    k.apply(there)
    first = len(checked)
    k.apply(back)
    k.apply(there)
    assert len(checked) == 2 * first and k.get_predicates()[-1] == Atom("p", ("c",))
    k.remove_instance("c")
    with pytest.raises(KnowledgeError, match=r"predicate \(p c\): unknown object 'c'"):
        k.apply(there)
    assert len(checked) > 2 * first
    assert [c.reason for c in seen] == ["apply", "apply", "apply", "remove_instance"]
