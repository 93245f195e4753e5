"""The cooking experiment on the virtual clock: figures, faults, consistency."""

from __future__ import annotations

import json

import pytest

from plansys_bridge.cli import main
from plansys_bridge.experiments.cooking import CookingConfig, run_cooking
from plansys_bridge.performers.simulated import FaultPlan


def test_three_robots_work_in_parallel() -> None:
    stats = run_cooking(CookingConfig(robots=3, max_plans=6, battery_drops_per_hour=0))
    assert stats.missions == 6
    assert stats.failures == 0
    assert stats.dishes == 12
    assert stats.replans == 0
    assert stats.consistency_errors == []
    # three robots: summed action time well above the elapsed mission time
    assert stats.efficiency_percent > 150.0
    assert stats.action_time_s > stats.total_time_s


def test_one_robot_is_slower_than_three() -> None:
    one = run_cooking(CookingConfig(robots=1, max_plans=4, battery_drops_per_hour=0))
    three = run_cooking(CookingConfig(robots=3, max_plans=4, battery_drops_per_hour=0))
    assert one.dishes == three.dishes == 8
    assert one.total_time_s > three.total_time_s


def test_battery_drops_force_replans_and_recharges() -> None:
    stats = run_cooking(CookingConfig(robots=2, max_plans=8, battery_drops_per_hour=30, seed=3))
    assert stats.battery_drops > 0
    assert stats.replans > 0
    assert stats.failures == 0
    assert stats.dishes == 16
    assert stats.consistency_errors == []


def test_faults_end_in_reauctions_or_replans_never_a_hang() -> None:
    faults = FaultPlan(die_rate=0.05, lose_finish_rate=0.05, revive_after=20.0)
    stats = run_cooking(
        CookingConfig(
            robots=3,
            max_plans=12,
            faults=faults,
            unresponsive_per_hour=20.0,
            battery_drops_per_hour=6.0,
            seed=7,
        )
    )
    assert stats.missions == 12
    injected = stats.performer_deaths + stats.lost_finishes + stats.unresponsive_injected
    assert injected > 0
    assert stats.reauctioned_actions + stats.replans > 0
    assert stats.consistency_errors == []
    assert stats.failures <= 1, stats.failure_reasons


def test_same_seed_same_figures() -> None:
    a = run_cooking(CookingConfig(robots=2, max_plans=3, seed=11, battery_drops_per_hour=10))
    b = run_cooking(CookingConfig(robots=2, max_plans=3, seed=11, battery_drops_per_hour=10))
    keep = ("plans", "actions", "replans", "dishes", "total_time_s", "efficiency_percent")
    assert {k: getattr(a, k) for k in keep} == {k: getattr(b, k) for k in keep}


def test_experiment_command_json(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["experiment", "cooking", "--robots", "2", "--plans", "2", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0
    for key in (
        "plans",
        "actions",
        "replans",
        "failures",
        "dishes",
        "total_time_s",
        "efficiency_percent",
    ):
        assert key in data
    assert data["dishes"] == 4
    assert data["paper_efficiency_percent"] == 137.54


def test_experiment_command_rejects_bad_time_scale(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["experiment", "cooking", "--clock", "wall", "--time-scale", "0", "--plans", "1"])
    assert code == 2
    assert "time-scale" in capsys.readouterr().err
