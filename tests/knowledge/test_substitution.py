"""Substituting objects for variables: the walker's short ways (atoms of a
conjunction, adds and deletes of an effect handed straight on, one substitution
for a ground action's five parts) give what a plain recursive substitution,
written apart here, gives; binding an action checks its arguments as before."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.errors import KnowledgeError, SourceLocation
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.grounding import (
    substitute_condition,
    substitute_effect,
    substitution,
)
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    Atom,
    DeleteEffect,
    Exists,
    FluentRef,
    Not,
    Number,
    NumericEffect,
    Or,
    TypedName,
    WhenEffect,
)
from plansys_bridge.pddl.parser import parse_domain

TERMS = st.sampled_from(["?x", "?y", "?z", "k", "m"])
ARGS = st.lists(TERMS, max_size=3).map(tuple)
ATOMS = st.builds(
    lambda p, args, at: Atom(p, args, SourceLocation("d.pddl", at, 1)),
    st.sampled_from(["p", "q"]),
    ARGS,
    st.integers(1, 9),
)
CONDITIONS = st.recursive(
    ATOMS,
    lambda inner: st.one_of(
        st.lists(inner, max_size=3).map(lambda ops: And(tuple(ops))),
        st.lists(inner, max_size=2).map(lambda ops: Or(tuple(ops))),
        inner.map(Not),
        inner.map(lambda body: Exists((TypedName("?x"),), body)),  # ?x shadowed inside
    ),
    max_leaves=8,
)
FLUENTS = st.builds(FluentRef, st.just("level"), ARGS)
SIMPLE_EFFECTS = st.one_of(
    ATOMS.map(AddEffect),
    ATOMS.map(DeleteEffect),
    st.builds(
        lambda f, v: NumericEffect("increase", f, v),
        FLUENTS,
        st.one_of(FLUENTS, st.just(Number(1.0))),
    ),
    st.builds(WhenEffect, CONDITIONS, ATOMS.map(AddEffect)),
)
EFFECTS = st.one_of(
    SIMPLE_EFFECTS, st.lists(SIMPLE_EFFECTS, max_size=4).map(lambda es: AndEffect(tuple(es)))
)
BINDINGS = st.dictionaries(st.sampled_from(["?x", "?y"]), st.sampled_from(["a", "b"]))


def _args(args: tuple[str, ...], b: dict[str, str]) -> tuple[str, ...]:
    return tuple(b.get(a, a) if a.startswith("?") else a for a in args)


def _reference(node: Any, b: dict[str, str]) -> Any:
    """A plain recursive substitution; a quantifier's variables shadow ``b``."""
    if isinstance(node, Atom):
        return Atom(node.predicate, _args(node.args, b), node.loc)
    if isinstance(node, FluentRef):
        return FluentRef(node.name, _args(node.args, b), node.loc)
    if isinstance(node, And | Or):
        return type(node)(tuple(_reference(o, b) for o in node.operands))
    if isinstance(node, Not):
        return Not(_reference(node.operand, b))
    if isinstance(node, Exists):
        inner = {k: v for k, v in b.items() if k not in {v.name for v in node.variables}}
        return Exists(node.variables, _reference(node.body, inner))
    if isinstance(node, AddEffect | DeleteEffect):
        return type(node)(_reference(node.atom, b))
    if isinstance(node, AndEffect):
        return AndEffect(tuple(_reference(e, b) for e in node.effects))
    if isinstance(node, WhenEffect):
        return WhenEffect(_reference(node.condition, b), _reference(node.effect, b))
    if isinstance(node, NumericEffect):
        return NumericEffect(node.op, _reference(node.fluent, b), _reference(node.value, b))
    return node  # a number


def _locs(node: Any) -> list[object]:
    """Every atom's location, in order (equality leaves them out)."""
    if isinstance(node, Atom):
        return [node.loc]
    if isinstance(node, tuple):
        return [loc for part in node for loc in _locs(part)]
    fields = getattr(node, "__dataclass_fields__", None)
    if fields is None:
        return []
    return [loc for name in fields for loc in _locs(getattr(node, name))]


@given(cond=CONDITIONS, effect=EFFECTS, b=BINDINGS)
def test_substitution_is_the_plain_recursive_one(cond: Any, effect: Any, b: dict[str, str]) -> None:
    sub = substitution(b)
    for node, one in ((cond, substitute_condition), (effect, substitute_effect)):
        expected = _reference(node, b)
        for got in (sub(node), one(node, b)):
            assert got == expected and type(got) is type(expected)
            assert _locs(got) == _locs(expected)
    if not b:
        assert sub(cond) is cond and sub(effect) is effect


DOMAIN = parse_domain(
    """(define (domain g) (:requirements :typing :durative-actions)
      (:types place robot - object drone - robot crate)
      (:predicates (at ?r - robot ?p - place) (held ?c - (either crate robot)))
      (:durative-action go
        :parameters (?r - robot ?from ?to - place ?c - (either crate robot))
        :duration (= ?duration 2)
        :condition (and (at start (at ?r ?from)) (over all (held ?c)))
        :effect (and (at start (not (at ?r ?from))) (at end (at ?r ?to)))))""",
    "<g>",
)
OBJECTS = {"d1": "drone", "r1": "robot", "hall": "place", "lab": "place", "c1": "crate"}


@pytest.mark.parametrize(
    ("args", "error"),
    [
        (["d1", "hall", "lab", "c1"], None),  # a drone is a robot; either crate or robot
        (["R1", "Hall", "lab", "d1"], None),
        (["hall", "hall", "lab", "c1"], "hall is a place, parameter ?r wants robot"),
        (["r1", "hall", "lab", "hall"], "hall is a place, parameter ?c wants crate or robot"),
        (["r1", "nowhere", "lab", "c1"], "unknown object 'nowhere'"),
    ],
)
def test_binding_checks_objects_and_types(args: list[str], error: str | None) -> None:
    ev = Evaluator(DOMAIN)
    state = State(objects=OBJECTS)
    if error is not None:
        with pytest.raises(KnowledgeError) as got:
            ev.ground_action("go", args, state)
        assert str(got.value) == f"action (go {' '.join(a.lower() for a in args)}): {error}"
        return
    ground = ev.ground_action("go", args, state)
    r, src, dst, c = (a.lower() for a in args)
    assert ground.at_start == Atom("at", (r, src)) and ground.over_all == Atom("held", (c,))
    assert ground.start_effect == DeleteEffect(Atom("at", (r, src)))
    assert ground.end_effect == AddEffect(Atom("at", (r, dst)))
    assert ground.duration == 2.0
