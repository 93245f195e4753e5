"""The PDDL 2.1 mutex rule on numeric fluents (Fox & Long 2003, section 8), boundary
cases each checked against VAL's ``Validate`` (when installed): simultaneous
``increase``/``decrease`` of one fluent commute; an assignment or a scaling with
anything else on it, or a change to a fluent the other reads, interferes."""

from __future__ import annotations

from pathlib import Path

import pytest
from planning_corpus import val_binary, val_verdict

from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.planning.plan import parse_plan
from plansys_bridge.planning.validation import validate_plan

DOMAIN = """
(define (domain counters)
  (:requirements :typing :durative-actions :numeric-fluents)
  (:types item)
  (:predicates (ready ?i - item) (done ?i - item))
  (:functions (count) (step))
  (:durative-action inc :parameters (?i - item) :duration (= ?duration 2)
    :condition (at start (ready ?i))
    :effect (and (at start (not (ready ?i))) (at end (done ?i)) (at end (increase (count) 1))))
  (:durative-action dec :parameters (?i - item) :duration (= ?duration 2)
    :condition (at start (ready ?i))
    :effect (and (at start (not (ready ?i))) (at end (done ?i)) (at end (decrease (count) 1))))
  (:durative-action reset :parameters (?i - item) :duration (= ?duration 2)
    :condition (at start (ready ?i))
    :effect (and (at start (not (ready ?i))) (at end (done ?i)) (at end (assign (count) 10))))
  (:durative-action double :parameters (?i - item) :duration (= ?duration 2)
    :condition (at start (ready ?i))
    :effect (and (at start (not (ready ?i))) (at end (done ?i)) (at end (scale-up (count) 2))))
  (:durative-action check :parameters (?i - item) :duration (= ?duration 2)
    :condition (and (at start (ready ?i)) (at end (>= (count) 0)))
    :effect (and (at start (not (ready ?i))) (at end (done ?i))))
  (:durative-action inc-by-step :parameters (?i - item) :duration (= ?duration 2)
    :condition (at start (ready ?i))
    :effect (and (at start (not (ready ?i))) (at end (done ?i))
                 (at end (increase (count) (step)))))
  (:durative-action bump-step :parameters (?i - item) :duration (= ?duration 2)
    :condition (at start (ready ?i))
    :effect (and (at start (not (ready ?i))) (at end (done ?i)) (at end (increase (step) 1)))))
"""

PROBLEM = """
(define (problem two) (:domain counters)
  (:objects a b - item)
  (:init (ready a) (ready b) (= (count) 0) (= (step) 1))
  (:goal (and (done a) (done b))))
"""

CASES = [
    # (first action, second action, second start, valid)
    ("inc", "inc", "1.000", True),  # two increases commute
    ("inc", "dec", "1.000", True),  # an increase and a decrease commute
    ("inc", "inc", "1.0005", True),  # not mutex: no epsilon needed between them
    ("inc", "reset", "1.000", False),  # an assignment does not commute
    ("inc", "double", "1.000", False),  # nor does a scaling
    ("inc", "check", "1.000", False),  # a condition reads what the other changes
    ("inc-by-step", "bump-step", "1.000", False),  # the right-hand side is read
    ("inc-by-step", "inc", "1.000", True),  # both add to count; step is only read
    ("inc", "reset", "1.010", True),  # mutex but epsilon apart
]


@pytest.mark.parametrize(("first", "second", "at", "valid"), CASES)
def test_simultaneous_numeric_effects_follow_pddl21_mutex_rules(
    first: str, second: str, at: str, valid: bool, tmp_path: Path
) -> None:
    domain = parse_domain(DOMAIN, "<counters>")
    problem = parse_problem(PROBLEM, domain, "<two>")
    plan = parse_plan(f"1.000: ({first} a) [2.000]\n{at}: ({second} b) [2.000]\n")
    report = validate_plan(domain, problem, plan)
    assert report.valid is valid, report.message
    if not valid:
        assert "(count)" in report.message or "(step)" in report.message
    if val_binary() is not None:
        assert val_verdict(tmp_path, domain, problem, plan) is valid
