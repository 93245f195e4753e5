"""Small planning tasks the solver contract plans (PDDL text -> model): classical,
temporal, numeric and concurrent (required concurrency), and an unsolvable one."""

from __future__ import annotations

from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.pddl.parser import parse_domain, parse_problem

CLASSICAL_DOMAIN = """
(define (domain corridor)
  (:requirements :strips :typing)
  (:types robot room)
  (:predicates (at ?r - robot ?x - room) (connected ?a ?b - room))
  (:action go
    :parameters (?r - robot ?a ?b - room)
    :precondition (and (at ?r ?a) (connected ?a ?b))
    :effect (and (not (at ?r ?a)) (at ?r ?b))))
"""

CLASSICAL_PROBLEM = """
(define (problem corridor_1) (:domain corridor)
  (:objects r1 - robot a b c - room)
  (:init (at r1 a) (connected a b) (connected b c))
  (:goal (at r1 c)))
"""

CLASSICAL_UNSOLVABLE = """
(define (problem corridor_2) (:domain corridor)
  (:objects r1 - robot a b c - room)
  (:init (at r1 a) (connected a b) (connected c b))
  (:goal (at r1 c)))
"""

TEMPORAL_DOMAIN = """
(define (domain fleet)
  (:requirements :strips :typing :durative-actions)
  (:types robot room)
  (:predicates (robot_at ?r - robot ?x - room) (connected ?a ?b - room)
               (cleaned ?x - room))
  (:durative-action move
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration 5)
    :condition (and (at start (robot_at ?r ?a)) (over all (connected ?a ?b)))
    :effect (and (at start (not (robot_at ?r ?a))) (at end (robot_at ?r ?b))))
  (:durative-action clean
    :parameters (?r - robot ?x - room)
    :duration (= ?duration 10)
    :condition (and (over all (robot_at ?r ?x)))
    :effect (and (at end (cleaned ?x)))))
"""

TEMPORAL_PROBLEM = """
(define (problem fleet_1) (:domain fleet)
  (:objects r1 r2 - robot base k1 k2 - room)
  (:init (robot_at r1 base) (robot_at r2 base)
         (connected base k1) (connected base k2) (connected k1 base) (connected k2 base))
  (:goal (and (cleaned k1) (cleaned k2))))
"""

NUMERIC_DOMAIN = """
(define (domain energy)
  (:requirements :strips :typing :durative-actions :fluents)
  (:types robot room)
  (:predicates (robot_at ?r - robot ?x - room) (connected ?a ?b - room))
  (:functions (battery ?r - robot) (distance ?a ?b - room))
  (:durative-action move
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration (distance ?a ?b))
    :condition (and (at start (robot_at ?r ?a)) (at start (connected ?a ?b))
                    (at start (>= (battery ?r) (distance ?a ?b))))
    :effect (and (at start (not (robot_at ?r ?a))) (at end (robot_at ?r ?b))
                 (at end (decrease (battery ?r) (distance ?a ?b))))))
"""

NUMERIC_PROBLEM = """
(define (problem energy_1) (:domain energy)
  (:objects r1 - robot a b c - room)
  (:init (robot_at r1 a) (connected a b) (connected b c)
         (= (battery r1) 20) (= (distance a b) 4) (= (distance b c) 6))
  (:goal (robot_at r1 c)))
"""

# PlanSys2's match/fuse example: mending needs light, which only lighting a match
# gives while it burns, so mend must run inside light_match (required concurrency).
CONCURRENT_DOMAIN = """
(define (domain matchcellar)
  (:requirements :typing :durative-actions)
  (:types match fuse)
  (:predicates (handfree) (unused ?m - match) (mended ?f - fuse) (light))
  (:durative-action light_match
    :parameters (?m - match)
    :duration (= ?duration 8)
    :condition (and (at start (unused ?m)))
    :effect (and (at start (not (unused ?m))) (at start (light)) (at end (not (light)))))
  (:durative-action mend_fuse
    :parameters (?f - fuse)
    :duration (= ?duration 5)
    :condition (and (at start (handfree)) (over all (light)))
    :effect (and (at start (not (handfree))) (at end (mended ?f)) (at end (handfree)))))
"""

CONCURRENT_PROBLEM = """
(define (problem matchcellar_1) (:domain matchcellar)
  (:objects m1 - match f1 - fuse)
  (:init (unused m1) (handfree))
  (:goal (mended f1)))
"""


def load(domain_text: str, problem_text: str) -> tuple[Domain, Problem]:
    domain = parse_domain(domain_text, "domain.pddl")
    return domain, parse_problem(problem_text, domain, "problem.pddl")


def classical() -> tuple[Domain, Problem]:
    return load(CLASSICAL_DOMAIN, CLASSICAL_PROBLEM)


def classical_unsolvable() -> tuple[Domain, Problem]:
    return load(CLASSICAL_DOMAIN, CLASSICAL_UNSOLVABLE)


def temporal() -> tuple[Domain, Problem]:
    return load(TEMPORAL_DOMAIN, TEMPORAL_PROBLEM)


def numeric() -> tuple[Domain, Problem]:
    return load(NUMERIC_DOMAIN, NUMERIC_PROBLEM)


def concurrent() -> tuple[Domain, Problem]:
    return load(CONCURRENT_DOMAIN, CONCURRENT_PROBLEM)
