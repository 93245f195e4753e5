"""Footprints from lifted templates are the evaluator's, and what they skip is sound."""

from __future__ import annotations

import pytest
from tasks import concurrent, numeric, temporal

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.pddl.model import And, Atom, DeleteEffect, DurativeAction, Not
from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.planning.mutex import Footprints
from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.validation import initial_state, validate_plan


@pytest.mark.parametrize("task", [temporal, numeric, concurrent])
def test_templates_give_what_the_evaluator_finds(task: object) -> None:
    domain, problem = task()  # type: ignore[operator]
    plan = Planner().solve(domain, problem).plan
    assert plan is not None
    ev = Evaluator(domain)
    footprints = Footprints(ev)
    state = initial_state(domain, problem)
    compared = 0
    for step in plan.steps:
        action, bindings = ev.bind(step.action, step.arguments, state)
        if not isinstance(action, DurativeAction):
            continue
        for condition, effect in (
            (action.at_start, action.start_effect),
            (action.at_end, action.end_effect),
        ):
            assert footprints.of(condition, effect, bindings, state) == footprints._asked(
                condition, effect, dict(bindings), state
            )
            compared += 1
    assert compared


QUANTIFIED_DOMAIN = """
(define (domain guard)
  (:requirements :strips :typing :durative-actions :universal-preconditions)
  (:types robot room)
  (:predicates (at ?r - robot ?x - room) (open ?x - room) (watched ?x - room))
  (:durative-action watch
    :parameters (?r - robot ?x - room)
    :duration (= ?duration 10)
    :condition (and (at start (at ?r ?x))
                    (over all (forall (?y - room) (open ?y))))
    :effect (at end (watched ?x)))
  (:durative-action close
    :parameters (?r - robot ?x - room)
    :duration (= ?duration 2)
    :condition (at start (at ?r ?x))
    :effect (at end (not (open ?x)))))
"""

QUANTIFIED_PROBLEM = """
(define (problem guard_1) (:domain guard)
  (:objects r1 r2 - robot a b - room)
  (:init (at r1 a) (at r2 b) (open a) (open b))
  (:goal (watched a)))
"""


def test_an_over_all_condition_broken_mid_interval_is_found_through_a_quantifier() -> None:
    """The over-all condition reads every room: a change to any of them is checked."""
    from plansys_bridge.planning.plan import parse_plan

    domain = parse_domain(QUANTIFIED_DOMAIN)
    problem = parse_problem(QUANTIFIED_PROBLEM, domain)
    plan = parse_plan("0.000: (watch r1 a) [10.000]\n3.000: (close r2 b) [2.000]\n")
    report = validate_plan(domain, problem, plan)
    assert not report.valid
    assert report.failing_index == 0
    assert "over all condition" in report.message and "at 5" in report.message


@pytest.mark.parametrize("task", [temporal, numeric, concurrent])
def test_direct_lookups_agree_with_the_evaluator(task: object) -> None:
    """Literal conditions are looked up and plain effects applied without the
    evaluator; along a whole plan both give the same answers."""
    domain, problem = task()  # type: ignore[operator]
    plan = Planner().solve(domain, problem).plan
    assert plan is not None
    ev = Evaluator(domain)
    footprints = Footprints(ev)
    state = initial_state(domain, problem)
    for step in plan.sorted().steps:
        action, bindings = ev.bind(step.action, step.arguments, state)
        if not isinstance(action, DurativeAction):
            continue
        for condition, effect in (
            (action.at_start, action.start_effect),
            (action.over_all, action.end_effect),
            (action.at_end, action.end_effect),
        ):
            if footprints.holds(condition, bindings, state):
                assert ev.holds(condition, state, bindings, step.duration)
            quick = footprints.changes(effect, bindings)
            if quick is not None:
                adds, deletes, values = ev.changes(effect, state, bindings, step.duration)
                assert (sorted(map(str, quick[0])), sorted(map(str, quick[1]))) == (
                    sorted(map(str, adds)),
                    sorted(map(str, deletes)),
                )
                assert not values
        state = ev.apply(action.start_effect, state, bindings, step.duration)
        state = ev.apply(action.end_effect, state, bindings, step.duration)


def test_a_negative_literal_fails_as_the_evaluator_says() -> None:
    domain = parse_domain(QUANTIFIED_DOMAIN)
    problem = parse_problem(QUANTIFIED_PROBLEM, domain)
    ev = Evaluator(domain)
    footprints = Footprints(ev)
    state = initial_state(domain, problem)
    lifted = And((Atom("at", ("?r", "?x")), Not(Atom("open", ("?x",)))))
    bindings = {"?r": "r1", "?x": "a"}
    assert not footprints.holds(lifted, bindings, state)
    assert not ev.holds(lifted, state, bindings)
    closed = ev.apply(DeleteEffect(Atom("open", ("?x",))), state, bindings)
    assert footprints.holds(lifted, bindings, closed)
    assert ev.holds(lifted, closed, bindings)
