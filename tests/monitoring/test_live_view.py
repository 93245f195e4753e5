"""The live table (rich) drawn from a real run's watch, into a fake terminal."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission
from plansys_bridge.monitoring.watch import MissionWatch, WatchEvent

rich_console = pytest.importorskip("rich.console", reason="the ui extra (rich) is not installed")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def test_live_table_shows_states_completion_performers_and_failures() -> None:
    from plansys_bridge.monitoring.live import LiveView

    buffer = io.StringIO()
    console = rich_console.Console(file=buffer, force_terminal=True, width=200, color_system=None)
    view = LiveView(lambda: 12.5, title="demo", console=console)
    mission = load_mission(CONFIGS / "demo_cooking.yaml")
    mission = mission.model_copy(
        update={"clock": mission.clock.model_copy(update={"kind": "virtual"})}
    )
    # the view listens to a second watch on the same run, as run_mission wires it
    report = run_mission(mission, out=None)
    assert report.watch is not None and report.result is not None
    replayed = MissionWatch(lambda: 0.0, view)
    view.bind(replayed)
    with view:
        for plan in report.watch.plans:
            replayed.plans.append(plan)
        for action in report.watch.actions:
            if action.status == ActionStatus.FAILED:
                view(WatchEvent("status", 6.0, action=action))
        replayed.performers.update(report.watch.performers)
    text = buffer.getvalue()
    assert "demo  t=12.5 s  plan 2 (14 actions)" in text
    assert "FAILED    (transport robot1 salt_1_1 pantry_zone cooking_zone) - over all" in text
    last = text[text.rindex("plan 2 (14 actions)") :]
    for action in report.result.plans[1].steps:
        assert action.text in last
    assert last.count("100 %") == 14 and last.count("succeeded") == 14
    assert "robot3_arm: ready" in last and "robot1_base" in last
