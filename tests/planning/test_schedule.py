"""Rescheduling on the executor's plan graph: earlier, still valid, never worse."""

from __future__ import annotations

from dataclasses import replace

import pytest
import tasks

from plansys_bridge.planning.plan import Plan, parse_plan
from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.schedule import reschedule, reschedule_report
from plansys_bridge.planning.validation import validate_plan

SERIAL = """
0.000: (move r1 base k1)  [5.000]
5.001: (clean r1 k1)  [10.000]
15.002: (move r2 base k2)  [5.000]
20.003: (clean r2 k2)  [10.000]
"""


def test_independent_robots_run_in_parallel() -> None:
    domain, problem = tasks.temporal()
    plan = parse_plan(SERIAL)
    report = reschedule_report(plan, domain, problem)
    assert report.rescheduled, report.message
    assert report.makespan_before == pytest.approx(30.003)
    assert report.makespan_after == pytest.approx(15.001)
    assert report.gain == pytest.approx(15.002)
    assert report.validation is not None and report.validation.valid
    times = {s.text: s.time for s in report.plan}
    assert times["(move r2 base k2)"] == 0.0
    assert times["(clean r2 k2)"] == pytest.approx(5.001)
    assert "30.003 -> 15.001" in report.message
    assert reschedule(plan, domain, problem) == report.plan


def test_required_concurrency_is_kept() -> None:
    domain, problem = tasks.concurrent()
    plan = parse_plan("5.000: (light_match m1)  [8.000]\n7.000: (mend_fuse f1)  [5.000]\n")
    report = reschedule_report(plan, domain, problem)
    assert report.rescheduled, report.message
    steps = {s.action: s for s in report.plan}
    assert steps["light_match"].time == 0.0
    assert steps["light_match"].time < steps["mend_fuse"].time
    assert steps["mend_fuse"].end < steps["light_match"].end
    assert validate_plan(domain, problem, report.plan).valid


def test_tight_plan_is_kept() -> None:
    domain, problem = tasks.temporal()
    plan = Planner().solve(domain, problem).plan
    assert plan is not None
    report = reschedule_report(plan, domain, problem)
    assert not report.rescheduled
    assert report.plan == plan
    assert report.makespan_after == report.makespan_before
    assert "already as early" in report.message


def test_invalid_plan_is_not_rescheduled() -> None:
    domain, problem = tasks.temporal()
    plan = parse_plan("0.000: (clean r1 k1)  [10.000]\n")
    report = reschedule_report(plan, domain, problem)
    assert not report.rescheduled and report.plan == plan
    assert report.message.startswith("not rescheduled")
    assert "(robot_at r1 k1)" in report.message


def test_stretched_cooking_plan_shrinks_back() -> None:
    from plansys_bridge.experiments.cooking_world import cooking_domain_path
    from plansys_bridge.pddl.parser import parse_domain, parse_problem

    domain = parse_domain(cooking_domain_path().read_text(), "cooking_domain.pddl")
    problem = parse_problem(
        """(define (problem three) (:domain cooking)
          (:objects robot1 robot2 robot3 - robot
            cooking_zone fridge_zone pantry_zone watertap_zone recharge_zone - zone
            egg oil salt flour sugar - ingredient omelette cake - dish)
          (:init (is_cooking_zone cooking_zone) (is_fridge_zone fridge_zone)
            (is_pantry_zone pantry_zone) (is_watertap_zone watertap_zone)
            (is_recharge_zone recharge_zone)
            (robot_at robot1 cooking_zone) (robot_at robot2 cooking_zone)
            (robot_at robot3 cooking_zone)
            (battery_full robot1) (battery_full robot2) (battery_full robot3)
            (is_egg egg) (is_oil oil) (is_salt salt) (is_flour flour) (is_sugar sugar)
            (ingredient_at egg fridge_zone) (ingredient_at oil pantry_zone)
            (ingredient_at salt pantry_zone) (ingredient_at flour pantry_zone)
            (ingredient_at sugar pantry_zone) (is_omelette omelette) (is_cake cake))
          (:goal (and (dish_prepared omelette) (dish_prepared cake))))""",
        domain,
    )
    plan = Planner().solve(domain, problem).plan
    assert plan is not None
    stretched = Plan(
        tuple(replace(s, time=s.time + 2.0 * k) for k, s in enumerate(plan.sorted().steps))
    )
    assert validate_plan(domain, problem, stretched).valid
    report = reschedule_report(stretched, domain, problem)
    assert report.rescheduled, report.message
    assert report.makespan_after <= plan.makespan + 1e-6
    assert validate_plan(domain, problem, report.plan).valid
