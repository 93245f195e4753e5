"""The evaluator's short ways agree with its general ones: ground atoms and
conjunctions looked up in the state directly, effects of facts gathered without
an evaluation context, and an at-start effect's changes handed over once."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.knowledge import evaluation
from plansys_bridge.knowledge.context import EvalContext
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.reasoner import Changes
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    Atom,
    Compare,
    Condition,
    DeleteEffect,
    Effect,
    FluentRef,
    Not,
    Number,
    WhenEffect,
)
from plansys_bridge.pddl.parser import parse_domain

DOMAIN = parse_domain(
    """(define (domain d) (:requirements :typing :fluents :derived-predicates)
      (:types thing)
      (:predicates (p ?x - thing) (q ?x ?y - thing) (r ?x - thing))
      (:functions (level ?x - thing))
      (:derived (r ?x - thing) (p ?x)))""",
    "<d>",
)
OBJECTS = {"a": "thing", "b": "thing"}
TERMS = st.sampled_from(["a", "b", "?x"])
ATOMS = st.one_of(
    st.builds(lambda t: Atom("p", (t,)), TERMS),
    st.builds(lambda t, u: Atom("q", (t, u)), TERMS, TERMS),
    st.builds(lambda t: Atom("r", (t,)), TERMS),
)
LEAVES = st.one_of(
    ATOMS,
    st.builds(lambda t: Compare(">", FluentRef("level", (t,)), Number(1.0)), TERMS),
)
CONDITIONS = st.one_of(
    LEAVES,
    st.lists(LEAVES, max_size=4).map(lambda ops: And(tuple(ops))),
    st.lists(st.one_of(LEAVES, LEAVES.map(Not)), max_size=3).map(lambda ops: And(tuple(ops))),
)
FACTS = [Atom("p", (x,)) for x in "ab"] + [Atom("q", (x, y)) for x in "ab" for y in "ab"]
STATES = st.builds(
    lambda facts, level: State(facts, {} if level is None else {("level", ("a",)): level}, OBJECTS),
    st.lists(st.sampled_from(FACTS)),
    st.none() | st.floats(0, 3),
)


def _outcome(run: object) -> tuple[str, object]:
    try:
        return "value", run()  # type: ignore[operator]
    except Exception as exc:  # the same error, whichever way
        return type(exc).__name__, str(exc)


@settings(max_examples=300, deadline=None)
@given(cond=CONDITIONS, state=STATES)
def test_holds_agrees_with_the_general_evaluation(cond: Condition, state: State) -> None:
    ev = Evaluator(DOMAIN)
    general = _outcome(lambda: ev._holds(cond, {}, EvalContext(ev, state, None)))
    assert _outcome(lambda: ev.holds(cond, state)) == general
    assert _outcome(lambda: ev.holds(cond, state)) == general  # remembered, same answer


def test_plain_conditions_are_the_ones_looked_up_directly() -> None:
    ev = Evaluator(DOMAIN)
    assert ev._plain(And((Atom("p", ("a",)), Atom("q", ("a", "b")))))[1] == (
        ("p", ("a",)),
        ("q", ("a", "b")),
    )
    assert ev._plain(Atom("p", ("a",)))[1] == (("p", ("a",)),)
    assert ev._plain(And(()))[1] == ()
    for other in (Atom("r", ("a",)), Atom("p", ("?x",)), And((Not(Atom("p", ("a",))),))):
        assert ev._plain(other)[1] is None


def test_a_remembered_condition_is_told_apart_by_identity() -> None:
    ev = Evaluator(DOMAIN)
    state = State([Atom("p", ("a",))], {}, OBJECTS)
    asked = Atom("p", ("b",))
    # Another condition once lived at this id: its facts must not be used.
    ev._plain_facts[id(asked)] = (Atom("p", ("a",)), (("p", ("a",)),))
    assert not ev.holds(asked, state)
    assert ev.holds(Atom("p", ("a",)), state)


_EFFECT_PARTS = st.tuples(st.booleans(), ATOMS).map(
    lambda t: AddEffect(t[1]) if t[0] else DeleteEffect(t[1])
)
EFFECTS = st.one_of(
    _EFFECT_PARTS,
    st.lists(_EFFECT_PARTS, max_size=5).map(lambda es: AndEffect(tuple(es))),
    st.lists(
        st.one_of(_EFFECT_PARTS, ATOMS.map(lambda a: WhenEffect(Atom("p", ("a",)), AddEffect(a)))),
        max_size=4,
    ).map(lambda es: AndEffect(tuple(es))),
)


@settings(max_examples=300, deadline=None)
@given(effect=EFFECTS, state=STATES)
def test_changes_agree_with_the_general_walk(effect: Effect, state: State) -> None:
    ev = Evaluator(DOMAIN)

    def general() -> tuple[list[Atom], list[Atom], dict[object, float]]:
        gathered = Changes()
        ev._collect(effect, {}, EvalContext(ev, state, None), gathered)
        return gathered.adds, gathered.deletes, {}

    assert _outcome(lambda: ev.changes(effect, state)) == _outcome(general)


@settings(max_examples=200, deadline=None)
@given(effect=EFFECTS, states=st.lists(STATES, min_size=2, max_size=4))
def test_an_effect_asked_again_agrees_with_the_general_walk(
    effect: Effect, states: list[State]
) -> None:
    """One effect object asked about in several states (a remembered answer must
    be right in each), its answers changed by the caller in between."""
    ev = Evaluator(DOMAIN)
    for state in states:

        def general(state: State = state) -> tuple[list[Atom], list[Atom], dict[object, float]]:
            gathered = Changes()
            ev._collect(effect, {}, EvalContext(ev, state, None), gathered)
            return gathered.adds, gathered.deletes, {}

        got = _outcome(lambda state=state: ev.changes(effect, state))  # type: ignore[misc]
        assert got == _outcome(general)
        if got[0] == "value":
            adds, deletes, _ = got[1]  # type: ignore[misc]
            adds.append(Atom("p", ("z",)))  # a caller's own lists
            deletes.clear()


def test_facts_only_effects_are_worked_out_once_per_effect(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    ev = Evaluator(DOMAIN)
    worked: list[Effect] = []
    plain = evaluation._plain_changes

    def counted(effect: Effect) -> Any:
        worked.append(effect)
        return plain(effect)

    monkeypatch.setattr(evaluation, "_plain_changes", counted)
    effect = AndEffect((AddEffect(Atom("p", ("a",))), DeleteEffect(Atom("q", ("a", "b")))))
    equal = AndEffect((AddEffect(Atom("p", ("a",))), DeleteEffect(Atom("q", ("a", "b")))))
    answers = [
        ev.changes(effect, State([], {}, OBJECTS)),
        ev.changes(effect, State([Atom("p", ("a",))], {}, OBJECTS), None, 3.0),
        ev.changes(equal, State([], {}, OBJECTS)),
    ]
    assert worked == [effect, equal]  # by identity: an equal effect is worked out anew
    assert all(a == ([Atom("p", ("a",))], [Atom("q", ("a", "b"))], {}) for a in answers)
    assert answers[0][0] is not answers[1][0]
    assert ev.plain_changes(effect) == ((Atom("p", ("a",)),), (Atom("q", ("a", "b")),))
    assert ev.plain_changes(WhenEffect(Atom("p", ("a",)), AddEffect(Atom("p", ("b",))))) is None
    unbound = AddEffect(Atom("p", ("?x",)))
    for _ in range(2):  # an error is not remembered: it is raised every time
        with pytest.raises(evaluation.UnboundVariableError, match=r"variable \?x is not bound"):
            ev.changes(unbound, State([], {}, OBJECTS))
    assert worked[3:] == [unbound, unbound]


def test_facts_only_effects_skip_the_walk(monkeypatch: pytest.MonkeyPatch) -> None:
    """Guards the comparison above against a short way that is never taken."""
    ev = Evaluator(DOMAIN)
    walked: list[Effect] = []
    collect = ev._collect

    def walk(effect: Effect, *rest: Any) -> None:
        walked.append(effect)
        collect(effect, *rest)

    monkeypatch.setattr(ev, "_collect", walk)
    state = State([], {}, OBJECTS)
    plain = AndEffect((AddEffect(Atom("p", ("a",))), DeleteEffect(Atom("p", ("b",)))))
    assert ev.changes(plain, state)[:2] == ([Atom("p", ("a",))], [Atom("p", ("b",))])
    assert walked == []
    when = WhenEffect(Atom("p", ("a",)), AddEffect(Atom("p", ("b",))))
    ev.changes(when, state)
    assert walked == [when]


def test_has_all_is_every_fact() -> None:
    state = State([Atom("p", ("a",)), Atom("q", ("a", "b"))], {}, OBJECTS)
    assert state.has_all([("p", ("a",)), ("q", ("a", "b"))]) and state.has_all([])
    assert not state.has_all([("p", ("a",)), ("q", ("b", "a"))])
    assert not state.has_all([("nothing", ())])


@given(state=STATES)
def test_the_empty_conjunction_holds_at_once(state: State) -> None:
    """TRUE (a ground action without a condition) holds in every state, answered
    before any look-up; with bindings it goes the way it went (bad ones still fail)."""
    ev = Evaluator(DOMAIN)
    for empty in (And(()), And(())):  # each ground action makes its own
        assert ev.holds(empty, state) is True
        assert ev._holds(empty, {}, EvalContext(ev, state, None)) is True
    assert ev._plain_facts == {}  # answered before the per-condition memory
    assert ev.holds(And(()), state, {"x": "a"}) is True
    bad = {"x": 3}  # not a name: normalising the bindings fails, as for any condition
    assert _outcome(lambda: ev.holds(And(()), state, bad)) == _outcome(
        lambda: ev.holds(Atom("p", ("a",)), state, bad)
    )
    assert _outcome(lambda: ev.holds(And(()), state, bad))[0] == "AttributeError"
