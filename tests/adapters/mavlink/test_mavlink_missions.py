"""Whole missions through the executor: plan, auction, fly and drive, on doubles."""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from typing import Any

import pytest
import yaml
from mavlink_support import CONFIGS, SPEEDUP
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from pymavlink.dialects.v20 import ardupilotmega as ml

from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import MissionReport, run_mission
from plansys_bridge.mission_config import mission_from_dict

FAST_TIMEOUTS = {"heartbeat": 1.0, "command": 0.5, "ekf": 20, "arm": 10, "action": 30}


def load(name: str) -> dict[str, Any]:
    data = yaml.safe_load((CONFIGS / name).read_text())
    assert isinstance(data, dict)
    return data


def fast(data: dict[str, Any]) -> dict[str, Any]:
    """The shipped mission with its doubles at test speed."""
    for entry in data["performers"]:
        if "double" in entry:
            entry["double"] = {**entry["double"], "speedup": SPEEDUP, "ekf_delay": 4.0}
        entry["timeouts"] = FAST_TIMEOUTS
        entry["heartbeat_period"] = 0.2
    data["auction"] = {**data.get("auction", {}), "retry_period": 0.2, "liveness_timeout": 3.0}
    return data


def run(data: dict[str, Any]) -> MissionReport:
    mission = mission_from_dict(data, source="test", base_dir=CONFIGS)
    lines: list[str] = []
    report = run_mission(mission, out=lines.append)
    assert report.result is not None, "\n".join(lines)
    return report


def test_fleet_mission_copter_and_rover_at_once() -> None:
    report = run(fast(load("mavlink_fleet.yaml")))
    assert report.success, report.summary()
    assert report.result is not None
    records = report.result.actions
    assert all(r.status == ActionStatus.SUCCEEDED for r in records)
    by_vehicle = {r.performer for r in records if " uav1 " in r.text}
    assert by_vehicle == {"uav1_performer"}
    assert {r.performer for r in records if " ugv1 " in r.text} == {"ugv1_performer"}
    # the copter and the rover really ran at the same time
    first_drive = min(r.start or 0 for r in records if r.text.startswith("(drive"))
    last_fly = max(r.end or 0 for r in records if r.text.startswith("(fly"))
    assert first_drive < last_fly
    assert report.result.efficiency_percent > 100.0


def test_single_vehicle_missions() -> None:
    for name in ("mavlink_copter.yaml", "mavlink_rover.yaml"):
        report = run(fast(load(name)))
        assert report.success, f"{name}: {report.summary()}"


def test_nearest_vehicle_wins_each_visit() -> None:
    # the plan names no vehicle: each visit goes to the lowest bid, the nearest one
    report = run(fast(load("mavlink_nearest.yaml")))
    assert report.success, report.summary()
    assert report.result is not None
    visits = {r.text: r.performer for r in report.result.actions if r.text.startswith("(visit")}
    assert visits == {
        "(visit tower)": "uav1_performer",
        "(visit orchard)": "uav2_performer",
        "(visit gate)": "ugv1_performer",
    }
    assert all(r.status == ActionStatus.SUCCEEDED for r in report.result.actions)


def copter_mission_with_fault(inject: Any, max_replans: int) -> tuple[str, MissionReport]:
    """Run the copter mission on a double of ours; ``inject(double)`` 20 m into the first leg."""
    # slow cruise (60 m take 0.75 s of wall time) so the fault lands mid-flight
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=4.0, cruise_speed=2.0) as double:
        data = fast(load("mavlink_copter.yaml"))
        entry = data["performers"][0]
        del entry["double"]
        entry["url"] = double.url
        data["replanning"] = {"max_replans": max_replans}

        def injector() -> None:
            if double.wait_for(lambda s: s["north"] > 20, timeout=30):
                inject(double)

        thread = threading.Thread(target=injector, name="fault-injector")
        thread.start()
        try:
            report = run(data)
        finally:
            thread.join()
    return double.url, report


def failed_actions(report: MissionReport) -> list[tuple[str, str]]:
    assert report.result is not None
    return [(r.text, r.message) for r in report.result.actions if r.status == ActionStatus.FAILED]


@pytest.mark.parametrize(
    ("inject", "reason"),
    [
        (lambda d: d.failsafe("Battery"), "failsafe: 'Battery Failsafe'"),
        (
            lambda d: d.statustext("Crash: Disarming", ml.MAV_SEVERITY_CRITICAL),
            "vehicle reported MAV_SEVERITY_CRITICAL: 'Crash: Disarming'",
        ),
        (lambda d: d.drop_link(1000.0), "no HEARTBEAT for "),
    ],
    ids=["failsafe", "statustext", "heartbeat"],
)
def test_fault_mid_mission_fails_cleanly_with_the_reason(
    inject: Callable[[VehicleDouble], None], reason: str
) -> None:
    url, report = copter_mission_with_fault(inject, max_replans=0)
    assert not report.success
    [(text, message)] = failed_actions(report)
    assert text == "(fly uav1 pad north_field)"
    assert message.startswith(f"{url}: {reason}")


def test_low_battery_halts_the_flight_and_the_copter_lands() -> None:
    # telemetry puts (battery_low uav1) into the knowledge; fly needs it false over
    # all, so the executor halts the flight (CANCEL: the copter lands) and replans
    states: list[Mapping[str, Any]] = []

    def low_battery(double: VehicleDouble) -> None:
        double.set_battery(15.0)
        double.wait_for(lambda s: s["mode"] == "LAND", timeout=10)
        states.append(double.state())

    _, report = copter_mission_with_fault(low_battery, max_replans=1)
    assert not report.success
    assert report.status == "replan_failed"
    assert failed_actions(report) == [
        (
            "(fly uav1 pad north_field)",
            "over all requirement (not (battery_low uav1)) no longer holds",
        )
    ]
    [state] = states
    assert state["mode"] == "LAND"
    assert 20 < state["north"] < 60


def test_mode_taken_over_mid_mission_is_replanned_and_completed() -> None:
    # someone switches to LOITER: the flight fails, the copter hovers, the executor
    # replans and the new plan's first flight takes GUIDED back
    url, report = copter_mission_with_fault(lambda d: d.change_mode("LOITER"), max_replans=1)
    assert report.success, report.summary()
    assert report.result is not None and report.result.replans == 1
    assert failed_actions(report) == [
        (
            "(fly uav1 pad north_field)",
            f"{url}: mode changed to LOITER by someone else (expected GUIDED)",
        )
    ]


def test_refused_takeoff_fails_the_mission_with_the_reason() -> None:
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=4.0) as double:
        double.refuse_next(ml.MAV_CMD_NAV_TAKEOFF, ml.MAV_RESULT_DENIED)
        data = fast(load("mavlink_copter.yaml"))
        entry = data["performers"][0]
        del entry["double"]
        entry["url"] = double.url
        data["replanning"] = {"max_replans": 0}
        report = run(data)
    assert not report.success
    assert report.result is not None
    failed = [r for r in report.result.actions if r.status == ActionStatus.FAILED]
    assert [r.text for r in failed] == ["(takeoff uav1 pad)"]
    assert failed[0].message == (f"{double.url}: MAV_CMD_NAV_TAKEOFF refused (MAV_RESULT_DENIED)")
