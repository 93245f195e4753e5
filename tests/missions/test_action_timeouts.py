"""Per-action overrun limits from the mission (PlanSys2's ``action_timeouts``), on
the real executor with simulated performers on the virtual clock."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

DOMAIN = Path(__file__).resolve().parents[1] / "data" / "simple_example.pddl"

MISSION = """
name: timeouts
domain: {domain}
knowledge:
  instances: {{leia: robot, entrance: room, dinning: room}}
  predicates: [(connected entrance dinning), (battery_full leia), (robot_at leia entrance)]
goal: (and (robot_at leia dinning))
performers:
  - kind: simulated
    name: leia_base
    actions: {{move: [leia]}}
    durations: {{move: 9}}
clock: {{kind: virtual}}
replanning: {{max_replans: 0}}
execution: {execution}
"""


def _run(tmp_path: Path, execution: str):  # type: ignore[no-untyped-def]
    path = tmp_path / "m.yaml"
    path.write_text(MISSION.format(domain=DOMAIN, execution=execution))
    return run_mission(load_mission(path), out=None)


def test_an_action_limit_fails_an_overrunning_action(tmp_path: Path) -> None:
    # the plan says 5 s, the robot takes 9 s: 50 % over is the most move may take
    report = _run(tmp_path, "{action_timeouts: {move: {duration_overrun_percentage: 50}}}")
    assert not report.success and report.result is not None
    (move,) = report.result.actions
    assert move.status == ActionStatus.FAILED
    assert "overran its planned duration 5 s by more than 50 %" in move.message
    assert move.end == pytest.approx(7.5)


def test_the_action_limit_overrides_the_global_one(tmp_path: Path) -> None:
    report = _run(
        tmp_path,
        "{overrun_percentage: 10, action_timeouts: {MOVE: {duration_overrun_percentage: 100}}}",
    )
    assert report.success, report.summary()
    assert _run(tmp_path, "{overrun_percentage: 10}").success is False


def test_bad_action_limits_name_their_key(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"execution\.action_timeouts\.move\.overrun"):
        _run(tmp_path, "{action_timeouts: {move: {overrun: 5}}}")
    with pytest.raises(ConfigError, match=r"action_timeouts\.move\.at_start_timeout"):
        _run(tmp_path, "{action_timeouts: {move: {at_start_timeout: -1}}}")
