"""Plan balancing: overlapping steps of one performer go to a free object of their type,
only when the validator accepts the plan and the robots finish sooner."""

from __future__ import annotations

import pytest

from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.planning.balance import (
    balance_plan,
    executed_makespan,
    overlapping_steps,
    performer_of,
)
from plansys_bridge.planning.plan import Plan, PlanStep, parse_plan
from plansys_bridge.planning.validation import validate_plan

DOMAIN = """
(define (domain kitchen)
  (:requirements :strips :typing :durative-actions)
  (:types robot zone dish item)
  (:predicates (at ?r - robot ?z - zone) (kitchen ?z - zone) (cooked ?d - dish)
               (item_at ?i - item ?z - zone) (holding ?r - robot ?i - item)
               (delivered ?i - item))
  (:durative-action move
    :parameters (?r - robot ?from ?to - zone)
    :duration (= ?duration 4)
    :condition (at start (at ?r ?from))
    :effect (and (at start (not (at ?r ?from))) (at end (at ?r ?to))))
  (:durative-action cook
    :parameters (?r - robot ?z - zone ?d - dish)
    :duration (= ?duration 20)
    :condition (and (at start (kitchen ?z)) (over all (at ?r ?z)))
    :effect (at end (cooked ?d)))
  (:durative-action grab
    :parameters (?r - robot ?i - item ?z - zone)
    :duration (= ?duration 5)
    :condition (and (over all (at ?r ?z)) (at start (item_at ?i ?z)))
    :effect (and (at start (not (item_at ?i ?z))) (at end (holding ?r ?i))))
  (:durative-action deliver
    :parameters (?r - robot ?i - item)
    :duration (= ?duration 3)
    :condition (at start (holding ?r ?i))
    :effect (and (at start (not (holding ?r ?i))) (at end (delivered ?i)))))
"""


def task(robots: str, init: str, goal: str) -> tuple[Domain, Problem]:
    domain = parse_domain(DOMAIN, "kitchen.pddl")
    problem = parse_problem(
        f"""(define (problem p) (:domain kitchen)
          (:objects {robots} - robot k hall - zone soup stew - dish cup plate - item)
          (:init (kitchen k) {init})
          (:goal {goal}))""",
        domain,
        "p.pddl",
    )
    return domain, problem


TWO_COOKS = """
0.000: (cook r1 k soup)  [20.000]
0.000: (cook r1 k stew)  [20.000]
"""
COOKED = "(and (cooked soup) (cooked stew))"


def test_two_cooks_of_one_robot_one_goes_to_the_free_robot() -> None:
    domain, problem = task("r1 r2", "(at r1 k) (at r2 k)", COOKED)
    plan = parse_plan(TWO_COOKS)
    assert overlapping_steps(plan) == [0, 1]
    assert executed_makespan(plan) == pytest.approx(40.0)
    balanced = balance_plan(domain, problem, plan)
    assert executed_makespan(balanced.plan) == pytest.approx(20.0)
    assert (balanced.before, balanced.after) == pytest.approx((40.0, 20.0))
    assert {performer_of(s) for s in balanced.plan} == {("cook", "r1"), ("cook", "r2")}
    assert len(balanced.handoffs) == 1
    handoff = balanced.handoffs[0]
    assert (handoff.source, handoff.target) == ("r1", "r2")
    assert balanced.plan.steps[handoff.steps[0]].arguments[0] == "r2"
    assert validate_plan(domain, problem, balanced.plan).valid
    assert overlapping_steps(balanced.plan) == []


def test_no_robot_free_for_the_step_leaves_the_plan_as_it_is() -> None:
    # r2 cooks during the whole interval: its cook performer is taken
    domain, problem = task("r1 r2", "(at r1 k) (at r2 k)", COOKED)
    plan = parse_plan(TWO_COOKS + "0.000: (cook r2 k soup)  [20.000]\n")
    balanced = balance_plan(domain, problem, plan)
    assert balanced.plan == plan
    assert balanced.handoffs == ()
    assert balanced.refused == 0
    # a single robot: nobody to hand to
    domain, problem = task("r1", "(at r1 k)", COOKED)
    alone = balance_plan(domain, problem, parse_plan(TWO_COOKS))
    assert alone.plan == parse_plan(TWO_COOKS)
    assert alone.after == pytest.approx(40.0)


def test_a_handoff_the_validator_refuses_is_not_made() -> None:
    # r2 is in the hall, not at the kitchen the cook needs over all
    domain, problem = task("r1 r2", "(at r1 k) (at r2 hall)", COOKED)
    plan = parse_plan(TWO_COOKS)
    handed = Plan((plan.steps[0], PlanStep(0.0, "cook", ("r2", "k", "stew"), 20.0)))
    assert not validate_plan(domain, problem, handed).valid
    balanced = balance_plan(domain, problem, plan)
    assert balanced.plan == plan
    assert balanced.handoffs == ()
    assert balanced.refused == 2  # either cook to r2


def test_later_steps_that_relied_on_the_handed_step_go_along() -> None:
    # r1 grabs both items at once and delivers them: deliver (r1 plate) needs r1 to
    # hold the plate, so when r2 grabs it, r2 delivers it too
    domain, problem = task(
        "r1 r2",
        "(at r1 k) (at r2 k) (item_at cup k) (item_at plate k)",
        "(and (delivered cup) (delivered plate))",
    )
    plan = parse_plan(
        "0.000: (grab r1 cup k)  [5.000]\n"
        "0.000: (grab r1 plate k)  [5.000]\n"
        "5.001: (deliver r1 cup)  [3.000]\n"
        "5.001: (deliver r1 plate)  [3.000]\n"
    )
    assert validate_plan(domain, problem, plan).valid
    balanced = balance_plan(domain, problem, plan)
    assert executed_makespan(plan) > balanced.after == pytest.approx(8.001)
    assert validate_plan(domain, problem, balanced.plan).valid
    (handoff,) = balanced.handoffs
    assert len(handoff.steps) == 2
    moved = {balanced.plan.steps[i].text for i in handoff.steps}
    assert moved in (
        {"(grab r2 cup k)", "(deliver r2 cup)"},
        {"(grab r2 plate k)", "(deliver r2 plate)"},
    )


def test_only_objects_of_the_parameter_type_are_tried() -> None:
    # dishes and zones are no robots: with one robot nothing is tried
    domain, problem = task("r1", "(at r1 k)", COOKED)
    balanced = balance_plan(domain, problem, parse_plan(TWO_COOKS))
    assert balanced.refused == 0
    assert balanced.handoffs == ()


def test_a_validation_budget_bounds_the_work() -> None:
    domain, problem = task("r1 r2", "(at r1 k) (at r2 hall)", COOKED)
    balanced = balance_plan(domain, problem, parse_plan(TWO_COOKS), max_validations=1)
    assert balanced.refused == 1
    assert balanced.plan == parse_plan(TWO_COOKS)


def test_a_valid_handoff_that_finishes_no_sooner_is_not_made() -> None:
    # r1's second grab waits 5 s for its first, but r2's cook ends the plan later anyway
    domain, problem = task(
        "r1 r2", "(at r1 k) (at r2 k) (item_at cup k) (item_at plate k)", "(cooked soup)"
    )
    plan = parse_plan(
        "0.000: (grab r1 cup k)  [5.000]\n"
        "0.000: (grab r1 plate k)  [5.000]\n"
        "0.000: (cook r2 k soup)  [20.000]\n"
    )
    handed = Plan((plan.steps[0], PlanStep(0.0, "grab", ("r2", "plate", "k"), 5.0), plan.steps[2]))
    assert validate_plan(domain, problem, handed).valid
    assert executed_makespan(handed) == executed_makespan(plan) == pytest.approx(20.0)
    balanced = balance_plan(domain, problem, plan)
    assert balanced.plan == plan
    assert balanced.handoffs == ()
