"""Footprints from lifted templates are the evaluator's, and what they skip is sound."""

from __future__ import annotations

import pytest
from tasks import concurrent, numeric, temporal

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.pddl.model import DurativeAction
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
