"""Whole missions through ``run_mission`` and the CLI, on the virtual clock."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from plansys_bridge.cli import main
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _demo(**clock: object):  # type: ignore[no-untyped-def]
    mission = load_mission(CONFIGS / "demo_cooking.yaml")
    return mission.model_copy(update={"clock": mission.clock.model_copy(update=clock)})


def test_demo_mission_replans_after_the_battery_drop() -> None:
    lines: list[str] = []
    report = run_mission(_demo(kind="virtual"), out=lines.append)
    assert report.success, report.summary()
    result = report.result
    assert result is not None
    assert result.replans == 1
    failed = [a for a in result.actions if a.status == ActionStatus.FAILED]
    assert len(failed) == 1
    assert "battery_full robot1" in failed[0].message
    # the new plan recharges robot1, since the goal keeps every robot charged
    recharged = [
        a
        for a in result.actions
        if a.text.startswith("(recharge robot1") and a.status == ActionStatus.SUCCEEDED
    ]
    assert recharged
    assert report.events_applied == ["t=6 -(battery_full robot1)"]
    assert any("event: -(battery_full robot1)" in line for line in lines)
    # three robots in parallel: more action time than mission time
    assert result.efficiency_percent > 100.0


def test_parallel_robots_overlap_in_time() -> None:
    report = run_mission(_demo(kind="virtual"), out=None)
    assert report.result is not None
    spans = [
        (a.start, a.end, a.performer)
        for a in report.result.actions
        if a.start is not None and a.end is not None and a.status == ActionStatus.SUCCEEDED
    ]
    overlapping = {
        (p1, p2) for s1, e1, p1 in spans for s2, e2, p2 in spans if p1 < p2 and s1 < e2 and s2 < e1
    }
    robots = {p.split("_")[0] for pair in overlapping for p in pair}
    assert robots == {"robot1", "robot2", "robot3"}


def test_unreachable_goal_reports_no_plan(tmp_path: Path) -> None:
    mission = _demo(kind="virtual").model_copy(
        update={"goal": "(and (robot_at robot1 cooking_zone) (robot_at robot1 fridge_zone))"}
    )
    report = run_mission(mission, out=None)
    assert not report.success
    assert report.status == "no plan"
    assert report.result is None


def test_run_command_json(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", str(CONFIGS / "demo_cooking.yaml"), "--clock", "virtual", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["success"] is True
    assert out["replans"] == 1
    assert out["plans"] == 2
    assert {"actions", "failures", "total_time_s", "efficiency_percent"} <= set(out)


def test_run_command_with_plan_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    plan = tmp_path / "plan.txt"
    plan.write_text("0.000: (move robot1 cooking_zone recharge_zone)  [3.800]\n")
    mission = tmp_path / "m.yaml"
    mission.write_text(
        (CONFIGS / "demo_cooking.yaml")
        .read_text()
        .replace("domain: pddl/", f"domain: {CONFIGS}/pddl/")
        .replace("events:\n  - {at: 6.0, remove_predicate: (battery_full robot1)}\n", "")
    )
    code = main(["run", str(mission), "--plan", str(plan), "--clock", "virtual", "--json"])
    out = json.loads(capsys.readouterr().out)
    # the given plan moves robot1 only: the dishes are not done, so the executor replans
    assert code == 0, out
    assert out["replans"] >= 1
    assert out["records"][0]["action"] == "(move robot1 cooking_zone recharge_zone)"


def test_run_command_config_error_exit_code(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "domain: x.pddl\ngoal: (and)\nperformers: [{kind: simulatd, name: a, actions: [x]}]\n"
    )
    code = main(["run", str(bad), "--clock", "virtual"])
    err = capsys.readouterr().err
    assert code == 2
    assert "x.pddl" in err or "performers[0].kind" in err


def test_unknown_performer_kind_names_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (
        (CONFIGS / "demo_cooking.yaml")
        .read_text()
        .replace("domain: pddl/", f"domain: {CONFIGS}/pddl/")
        .replace("kind: simulated, name: robot2_arm", "kind: simulatd, name: robot2_arm")
    )
    bad = tmp_path / "m.yaml"
    bad.write_text(text)
    code = main(["run", str(bad), "--clock", "virtual"])
    err = capsys.readouterr().err
    assert code == 2
    assert "performers[3].kind" in err
    assert "simulatd" in err


def test_demo_command_runs_the_demo_mission(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["demo", "--clock", "virtual", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["mission"] == "demo_cooking"
    assert out["replans"] == 1
