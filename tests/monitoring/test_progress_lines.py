"""Progress lines of a real mission (executor, simulated performers, virtual clock):
who won each auction, and each replanned plan as soon as it is made."""

from __future__ import annotations

from pathlib import Path

from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def test_demo_progress_names_winners_and_prints_the_replan_when_made() -> None:
    mission = load_mission(CONFIGS / "demo_cooking.yaml")
    mission = mission.model_copy(
        update={"clock": mission.clock.model_copy(update={"kind": "virtual"})}
    )
    lines: list[str] = []
    report = run_mission(mission, out=lines.append)
    assert report.success and report.result is not None
    result = report.result
    # every action a performer was confirmed for is announced with its winner
    served = [a for a in result.actions if a.performer]
    assigned = [line for line in lines if " ASSIGNED  " in line]
    assert len(assigned) == len(served) > 0
    for record in served:
        assert any(f"{record.text} -> {record.performer} (1 bid)" in line for line in assigned)
    # the replanned plan comes right after the failure, before its first action runs
    failed = next(i for i, line in enumerate(lines) if "FAILED    (transport robot1" in line)
    replanned = next(i for i, line in enumerate(lines) if "replanned (plan 2, " in line)
    recharge = next(
        i for i, line in enumerate(lines) if "EXECUTING (move robot1 pantry_zone" in line
    )
    assert failed < replanned < recharge
    second = result.plans[1].to_text().splitlines()
    assert [line.strip() for line in lines[replanned + 1 : replanned + 1 + len(second)]] == [
        line.strip() for line in second
    ]
    assert not any(line.startswith("replanned") for line in lines[recharge:])
    assert sum(1 for a in result.actions if a.status == ActionStatus.FAILED) == 1
