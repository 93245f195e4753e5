"""The cooking experiment's planner keeps the plan its robots finish first."""

from __future__ import annotations

import pytest

from plansys_bridge.experiments.cooking import (
    PORTFOLIO,
    CookingConfig,
    PortfolioPlanner,
    executed_makespan,
    run_cooking,
)
from plansys_bridge.planning.plan import parse_plan


def test_executed_makespan_runs_one_action_kind_of_a_robot_at_a_time() -> None:
    parallel = parse_plan(
        "0.000: (cook r1 a) [21.000]\n0.000: (cook r2 b) [21.000]\n21.001: (move r1 x y) [4.000]\n"
    )
    assert executed_makespan(parallel) == parallel.makespan
    # two cooks of r1 at once: its single cook performer runs them one after the other,
    # and r1's later move is delayed as much
    doubled = parse_plan(
        "0.000: (cook r1 a) [21.000]\n0.000: (cook r1 b) [21.000]\n21.001: (move r1 x y) [4.000]\n"
    )
    assert doubled.makespan == pytest.approx(25.001)
    assert executed_makespan(doubled) == pytest.approx(46.001)
    # different action kinds of one robot may overlap (separate performers)
    mixed = parse_plan("0.000: (cook r1 a) [21.000]\n0.000: (move r1 x y) [4.000]\n")
    assert executed_makespan(mixed) == pytest.approx(21.0)


def test_the_portfolio_plans_missions_and_replans_with_no_failure() -> None:
    stats = run_cooking(CookingConfig(robots=3, max_plans=4, battery_drops_per_hour=0))
    plain = run_cooking(
        CookingConfig(robots=3, max_plans=4, battery_drops_per_hour=0, plan_portfolio=False)
    )
    assert stats.failures == plain.failures == 0
    assert stats.dishes == plain.dishes == 8
    # never longer than Kairos' first plan alone on the same orders
    assert stats.total_time_s <= plain.total_time_s + 1e-6
    assert len(PortfolioPlanner().alternatives) == len(PORTFOLIO) == 2
