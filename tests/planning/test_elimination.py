"""Greedy action elimination: useless steps (a pick undone by the next drop, a move
there and back) leave the plan; needed ones stay; the result is valid."""

from __future__ import annotations

from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.planning.elimination import eliminate_redundant_steps
from plansys_bridge.planning.plan import parse_plan
from plansys_bridge.planning.validation import validate_plan

DOMAIN = """
(define (domain delivery)
  (:requirements :typing :durative-actions :numeric-fluents)
  (:types robot place box)
  (:predicates (at ?r - robot ?p - place) (box-at ?b - box ?p - place)
               (holding ?r - robot ?b - box) (free ?r - robot))
  (:functions (delivered))
  (:durative-action move :parameters (?r - robot ?a ?b - place) :duration (= ?duration 2)
    :condition (at start (at ?r ?a))
    :effect (and (at start (not (at ?r ?a))) (at end (at ?r ?b))))
  (:durative-action pick :parameters (?r - robot ?b - box ?p - place) :duration (= ?duration 1)
    :condition (and (at start (at ?r ?p)) (at start (box-at ?b ?p)) (at start (free ?r)))
    :effect (and (at start (not (box-at ?b ?p))) (at start (not (free ?r)))
                 (at end (holding ?r ?b))))
  (:durative-action drop :parameters (?r - robot ?b - box ?p - place) :duration (= ?duration 1)
    :condition (and (at start (at ?r ?p)) (at start (holding ?r ?b)))
    :effect (and (at start (not (holding ?r ?b))) (at end (box-at ?b ?p)) (at end (free ?r))
                 (at end (increase (delivered) 1)))))
"""

PROBLEM = """
(define (problem one) (:domain delivery)
  (:objects r - robot a b - place x y - box)
  (:init (at r a) (box-at x a) (box-at y a) (free r) (= (delivered) 0))
  (:goal (box-at x b)))
"""

PLAN = """
0.000: (pick r y a) [1.000]
1.001: (drop r y a) [1.000]
2.002: (pick r x a) [1.000]
3.003: (move r a b) [2.000]
5.004: (move r b a) [2.000]
7.005: (move r a b) [2.000]
9.006: (drop r x b) [1.000]
"""


def test_useless_steps_are_removed_and_the_plan_stays_valid() -> None:
    domain = parse_domain(DOMAIN, "<delivery>")
    problem = parse_problem(PROBLEM, domain, "<one>")
    plan = parse_plan(PLAN)
    assert validate_plan(domain, problem, plan).valid
    report = eliminate_redundant_steps(domain, problem, plan)
    kept = [s.text for s in report.plan.steps]
    assert kept == ["(pick r x a)", "(move r a b)", "(drop r x b)"]
    removed = sorted(s.text for s in report.removed)
    assert removed == ["(drop r y a)", "(move r a b)", "(move r b a)", "(pick r y a)"]
    assert validate_plan(domain, problem, report.plan).valid
    assert "removed 4 step(s)" in report.message


def test_a_plan_without_useless_steps_is_kept_as_it_is() -> None:
    domain = parse_domain(DOMAIN, "<delivery>")
    problem = parse_problem(PROBLEM, domain, "<one>")
    plan = parse_plan(
        "0.000: (pick r x a) [1.000]\n1.001: (move r a b) [2.000]\n3.002: (drop r x b) [1.000]\n"
    )
    report = eliminate_redundant_steps(domain, problem, plan)
    assert report.removed == () and report.plan == plan and report.message == ""


def test_the_planner_eliminates_on_request_only() -> None:
    from plansys_bridge.planning.planner import Planner

    domain = parse_domain(DOMAIN, "<delivery>")
    problem = parse_problem(PROBLEM, domain, "<one>")
    plain = Planner(validate=True).solve(domain, problem)
    pruned = Planner(validate=True, eliminate=True).solve(domain, problem)
    assert plain.plan is not None and pruned.plan is not None
    assert len(pruned.plan) <= len(plain.plan)
    assert pruned.validation is not None and pruned.validation.valid
