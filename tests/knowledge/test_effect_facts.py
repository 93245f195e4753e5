"""The short ways of an effect's first application agree with the general ones:
``effect_facts`` (an effect's own atoms) with the evaluator's walk, and
admission's remembered type fits with the type hierarchy."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.grounding import effect_facts
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import (
    AddEffect,
    AndEffect,
    Atom,
    DeleteEffect,
    Effect,
    FluentRef,
    Number,
    NumericEffect,
    WhenEffect,
)
from plansys_bridge.pddl.parser import parse_domain

DOMAIN = parse_domain(
    """(define (domain d) (:requirements :typing :fluents)
      (:types vehicle place - object robot drone - vehicle)
      (:constants base - place)
      (:predicates (p ?x - vehicle) (q ?x - robot ?y - place) (r ?x - drone))
      (:functions (level ?x - vehicle)))""",
    "<d>",
)
OBJECTS = {"a": "robot", "b": "drone", "base": "place"}

_ATOMS = st.builds(
    Atom,
    st.sampled_from(["p", "q", "r"]),
    st.lists(st.sampled_from(["a", "b", "base", "?x"]), max_size=2).map(tuple),
)
_PART = st.one_of(
    st.builds(AddEffect, _ATOMS),
    st.builds(DeleteEffect, _ATOMS),
    st.just(NumericEffect("increase", FluentRef("level", ("a",)), Number(1.0))),
    st.builds(lambda a: WhenEffect(Atom("p", ("a",)), AddEffect(a)), _ATOMS),
)
_EFFECTS = st.one_of(_PART, st.lists(_PART, max_size=5).map(lambda ps: AndEffect(tuple(ps))))


def _outcome(work: object) -> object:
    try:
        return work()  # type: ignore[operator]
    except KnowledgeError as exc:
        return (type(exc), str(exc))


@settings(max_examples=300, deadline=None)
@given(effect=_EFFECTS)
def test_effect_facts_are_the_walks_atoms(effect: Effect) -> None:
    """None exactly when the evaluator's short way gives none, else equal atoms in
    the same order; a variable is the same error, raised first in both."""
    ev = Evaluator(DOMAIN)
    mine = _outcome(lambda: effect_facts(effect))
    theirs = _outcome(lambda: ev.plain_changes(effect))
    if theirs is None or _is_error(theirs):
        assert mine == theirs
        return
    assert isinstance(mine, tuple) and (tuple(mine[0]), tuple(mine[1])) == theirs
    # and the general walk (in any state) changes those facts
    general = ev.changes(effect, State([], {}, OBJECTS))
    assert general[:2] == (list(mine[0]), list(mine[1]))


def _is_error(outcome: object) -> bool:
    return isinstance(outcome, tuple) and isinstance(outcome[0], type)


def test_effect_facts_hands_out_the_effects_own_atoms() -> None:
    atom = Atom("p", ("a",))
    assert effect_facts(AndEffect((DeleteEffect(atom),))) == ([], [atom])
    assert effect_facts(AndEffect((DeleteEffect(atom),)))[1][0] is atom  # type: ignore[index]
    assert effect_facts(AddEffect(Atom("p", ["a"]))) is None  # type: ignore[arg-type]


def test_remembered_type_fits_are_the_hierarchys() -> None:
    k = ProblemExpert(DOMAIN)
    types = ["object", "vehicle", "place", "robot", "drone"]
    wanted_sets = [(t,) for t in types] + [("robot", "drone"), ("place", "drone")]
    for _ in range(2):  # worked out, then remembered
        for obj_type in types:
            for wanted in wanted_sets:
                assert k._admit._fits(obj_type, wanted) == k._types.is_subtype_of_any(
                    (obj_type,), wanted
                )


@pytest.mark.parametrize(
    ("fact", "message"),
    [
        (
            Atom("q", ("b", "base")),
            r"predicate \(q b base\): b is a drone, parameter \?x wants robot",
        ),
        (Atom("q", ("a", "zed")), r"predicate \(q a zed\): unknown object 'zed'"),
        (Atom("q", ("a",)), r"predicate \(q a\): expects 2 arguments, got 1"),
        (Atom("r", ("a",)), r"predicate \(r a\): a is a robot, parameter \?x wants drone"),
    ],
)
def test_a_bad_fact_is_refused_the_same_way_twice(fact: Atom, message: str) -> None:
    """Applied and added, first and again (type fits remembered in between)."""
    k = ProblemExpert(DOMAIN)
    for name, typ in OBJECTS.items():
        if name != "base":
            k.add_instance(name, typ)
    for _ in range(2):
        with pytest.raises(KnowledgeError, match=message):
            k.apply(AddEffect(fact))
        with pytest.raises(KnowledgeError, match=message):
            k.add_predicate(fact)
    assert k.get_predicates() == []
