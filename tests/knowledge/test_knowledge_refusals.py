"""The knowledge base refuses what it cannot hold, at its API as in its text form.

NaN, infinities, integers beyond a float and values of the wrong Python type are
refused with a KnowledgeError (or the parser's PddlError for text) and change nothing;
whatever is accepted can always be written as PDDL, read back, published and checked.
"""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from knowledge_paths import PROBLEM_EXPERT_PDDL

from plansys_bridge.errors import KnowledgeError, PlansysBridgeError
from plansys_bridge.knowledge.context import EvaluationError
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import (
    And,
    Atom,
    BinaryOp,
    Compare,
    FluentRef,
    FluentValue,
    Not,
    Number,
)
from plansys_bridge.pddl.parser import parse_condition, parse_problem

DOMAIN = DomainExpert.from_files([PROBLEM_EXPERT_PDDL / "domain_charging.pddl"])
"""Robots and waypoints; functions speed/max_range/state_of_charge (robot), distance."""


def _expert() -> ProblemExpert:
    pe = ProblemExpert(DOMAIN)
    pe.add_instance("r1", "robot")
    pe.add_instance("wp1", "waypoint")
    pe.add_instance("wp2", "waypoint")
    pe.set_function("(= (speed r1) 2)")
    return pe


SPEED = FluentRef("speed", ("r1",))
BAD_NUMBERS = [math.nan, math.inf, -math.inf, 10**400, -(10**400), "3", None, True, 1j]


@pytest.mark.parametrize("value", BAD_NUMBERS, ids=repr)
def test_function_values_that_are_not_finite_floats_are_refused(value: Any) -> None:
    pe = _expert()
    before = pe.get_problem_text()
    with pytest.raises(KnowledgeError, match=r"\(speed r1\)"):
        pe.set_function(FluentValue(SPEED, value))
    assert pe.get_problem_text() == before
    assert pe.get_function("speed", ["r1"]) == 2.0


@pytest.mark.parametrize("text", ["nan", "inf", "-inf", "1" + "0" * 400, "1e400"])
def test_function_values_in_text_are_refused(text: str) -> None:
    pe = _expert()
    with pytest.raises(PlansysBridgeError):
        pe.set_function(f"(= (speed r1) {text})")
    with pytest.raises(PlansysBridgeError):
        pe.set_goal(f"(> (speed r1) {text})")
    assert pe.get_function("speed", ["r1"]) == 2.0
    assert pe.get_goal() is None


@pytest.mark.parametrize("value", BAD_NUMBERS, ids=repr)
def test_goal_numbers_that_are_not_finite_floats_are_refused(value: Any) -> None:
    pe = _expert()
    with pytest.raises(KnowledgeError):
        pe.set_goal(Compare(">", SPEED, Number(value)))
    with pytest.raises(KnowledgeError, match="not a numeric expression"):
        pe.set_goal(Compare(">", SPEED, value))
    assert pe.get_goal() is None


@pytest.mark.parametrize(
    "goal", [42, None, 1.5, "(", Not(42), And((Atom("patrolled", ("wp1",)), 7))], ids=repr
)
def test_goals_of_the_wrong_type_are_refused(goal: Any) -> None:
    pe = _expert()
    with pytest.raises(PlansysBridgeError):
        pe.set_goal(goal)
    assert pe.get_goal() is None
    pe.get_problem_text()


@pytest.mark.parametrize(
    ("method", "args"),
    [
        ("add_instance", (42, "robot")),
        ("add_instance", ("r9", None)),
        ("add_predicate", (42,)),
        ("add_predicate", (Atom("patrolled", (3,)),)),  # type: ignore[arg-type]
        ("remove_predicate", (None,)),
        ("set_function", (42,)),
        ("set_function", (FluentValue(FluentRef("speed", (1,)), 1.0),)),  # type: ignore[arg-type]
        ("remove_function", (42,)),
        ("get_function", (None,)),
    ],
)
def test_wrong_python_types_are_refused(method: str, args: tuple[Any, ...]) -> None:
    pe = _expert()
    before = pe.get_problem_text()
    with pytest.raises(KnowledgeError, match=r"must be text|not a"):
        getattr(pe, method)(*args)
    assert pe.get_problem_text() == before


def test_accepted_numbers_are_stored_as_floats() -> None:
    pe = _expert()
    pe.set_function(FluentValue(SPEED, 3))
    assert pe.get_function("speed", ["r1"]) == 3.0
    assert isinstance(pe.get_function("speed", ["r1"]), float)
    pe.set_goal(Compare(">=", SPEED, Number(10**300)))
    assert pe.is_goal_satisfied() is False


# ---------------------------------------------------------------- property test

NAMES = st.sampled_from(["r1", "r2", "wp1", "wp2", "wp3", "nobody"])
ANY_VALUE = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**420), max_value=10**420),
    st.booleans(),
    st.none(),
    st.text(max_size=4),
    st.integers(min_value=-5, max_value=5),
)
JUNK = st.one_of(st.integers(), st.none(), st.floats(), st.text(max_size=6))
ATOMS = st.one_of(
    st.builds(lambda a, b: Atom("robot_at", (a, b)), NAMES, NAMES),
    st.builds(lambda w: Atom("patrolled", (w,)), NAMES),
    st.builds(lambda a, b: f"(connected {a} {b})", NAMES, NAMES),
    JUNK,
)
FLUENTS = st.one_of(
    st.builds(lambda r: FluentRef("speed", (r,)), NAMES),
    st.builds(lambda a, b: FluentRef("distance", (a, b)), NAMES, NAMES),
)
EXPRS = st.one_of(
    st.builds(Number, ANY_VALUE),
    FLUENTS,
    st.builds(
        lambda op, f, v: BinaryOp(op, f, Number(v)), st.sampled_from("*/"), FLUENTS, ANY_VALUE
    ),
    st.builds(lambda v, f: BinaryOp("/", Number(v), f), ANY_VALUE, FLUENTS),
    JUNK,
)
GOALS = st.one_of(
    ATOMS,
    st.builds(
        lambda op, f, e: Compare(op, f, e), st.sampled_from(["<", ">=", "="]), FLUENTS, EXPRS
    ),
    st.builds(lambda a, b: And((a, b)), ATOMS, ATOMS),
    st.builds(
        lambda f, v: f"(> {f} {v!r})", st.sampled_from(["(speed r1)", "(speed r2)"]), ANY_VALUE
    ),
    JUNK,
)
CHANGES = st.one_of(
    st.tuples(st.just("add_instance"), NAMES, st.sampled_from(["robot", "waypoint", "thing"])),
    st.tuples(st.just("add_instance"), JUNK, JUNK),
    st.tuples(st.just("remove_instance"), NAMES),
    st.tuples(st.just("add_predicate"), ATOMS),
    st.tuples(st.just("remove_predicate"), ATOMS),
    st.tuples(st.just("set_function"), st.builds(FluentValue, FLUENTS, ANY_VALUE)),
    st.tuples(
        st.just("set_function"),
        st.builds(lambda r, v: f"(= (speed {r}) {v!r})", NAMES, ANY_VALUE),
    ),
    st.tuples(st.just("set_function"), JUNK),
    st.tuples(st.just("remove_function"), FLUENTS.map(lambda f: f"({f.name} {' '.join(f.args)})")),
    st.tuples(st.just("set_goal"), GOALS),
    st.tuples(st.just("clear_goal")),
)


def _snapshot(pe: ProblemExpert) -> tuple[str, object]:
    return pe.get_problem_text(), pe.get_goal()


def _still_whole(pe: ProblemExpert) -> None:
    """Written, read back, published and checked, whatever happened before."""
    text = pe.get_problem_text()
    reread = parse_problem(text, DOMAIN.domain)
    assert {str(a) for a in reread.init} == {str(a) for a in pe.get_predicates()}
    for fv in reread.init_fluents:
        assert math.isfinite(fv.value)
    msg = pe.to_msg()
    assert list(msg.predicates) == [str(a) for a in pe.get_predicates()]
    if msg.goal:
        parse_condition(msg.goal, DOMAIN.domain, objects=pe.get_instances())
    if pe.get_goal() is not None:
        fresh = ProblemExpert(DOMAIN)
        fresh.load_problem(text)
        assert _checked(fresh) == _checked(pe)


def _checked(pe: ProblemExpert) -> bool | str:
    """The goal checked: True/False, or the one EvaluationError that says why it cannot
    be decided now (a fluent it reads has no value, a divisor is zero); never anything
    else."""
    try:
        satisfied = pe.is_goal_satisfied()
    except EvaluationError as exc:
        assert "undefined" in str(exc) or "division by zero" in str(exc), str(exc)
        return str(exc)
    assert isinstance(satisfied, bool)
    return satisfied


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(CHANGES, min_size=1, max_size=12))
@example([("set_goal", "(> (speed r1) 1)"), ("remove_function", "(speed r1)")])
@example([("set_goal", "(> (/ 10 (speed r1)) 1)"), ("set_function", "(= (speed r1) 0)")])
def test_any_sequence_of_changes_leaves_a_whole_problem(changes: list[tuple[Any, ...]]) -> None:
    pe = _expert()
    for method, *args in changes:
        before = _snapshot(pe)
        try:
            getattr(pe, method)(*args)
        except PlansysBridgeError:
            assert _snapshot(pe) == before, f"refused {method}{tuple(args)!r} changed the knowledge"
        _still_whole(pe)
