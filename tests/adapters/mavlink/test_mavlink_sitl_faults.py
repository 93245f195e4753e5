"""Faults injected into real ArduPilot SITL through its own parameters and links.

The copter survey runs through ``plansys-bridge run``; a second ground station (on
SITL's SERIAL1 port) waits until the copter is well into its first leg, then injects
the fault the way ArduPilot's autotest does. Each time the action must end FAILED
with the vehicle's own reason (its STATUSTEXT, its HEARTBEAT or the ACK result)
within 3 s of the vehicle reporting it, the executor must replan or fail the mission
cleanly, and the vehicle must be left in a safe mode, as its HEARTBEAT shows.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import pytest
from plansys_bridge_adapters.mavlink.geo import offset
from plansys_bridge_adapters.mavlink.settings import Timeouts
from sitl_support import (
    GroundStation,
    Relay,
    Sitl,
    describe,
    finish_cli,
    sitl_mission,
    start_cli,
)

pytestmark = pytest.mark.sitl

SPEEDUP = 10.0
REPORT_WITHIN = 3.0
"""Seconds from the vehicle reporting a fault to the action's FINISH(failure)."""
COPTER_SAFE = ("BRAKE", "LAND", "RTL", "LOITER", "SMART_RTL")
FIRST_LEG = "(fly uav1 pad north_field)"


def failed(report: Mapping[str, Any]) -> list[tuple[str, str, float]]:
    return [
        (r["action"], r["message"], r["end"]) for r in report["records"] if r["status"] == "FAILED"
    ]


@contextlib.contextmanager
def survey_with_fault(
    gcs_url: str,
    url: str,
    tmp_path: Path,
    inject: Callable[[GroundStation], None] | None,
    replans: int = 0,
) -> Iterator[tuple[dict[str, Any], GroundStation, float]]:
    """The survey on ``url``; ``inject(gcs)`` 15 m into the first leg (None: no fault).
    Yields the report, the ground station on ``gcs_url`` and the injection time."""
    mission = sitl_mission("mavlink_copter.yaml", {"uav1": url}, tmp_path, replans=replans)
    proc = start_cli(mission)  # SITL opens its other ports once the adapter connects
    try:
        with GroundStation(gcs_url, "copter") as gcs:
            injected = 0.0
            if inject is not None:
                gcs.stream("GLOBAL_POSITION_INT", 10)
                on_leg = lambda s: s.north_max > 15 and s.alt > 8  # noqa: E731
                gcs.wait(lambda s: on_leg(s) or proc.poll() is not None, 120, "15 m into the leg")
                if not on_leg(gcs.seen):
                    raise AssertionError(f"ended before the fault: {describe(finish_cli(proc))}")
                injected = time.time()
                inject(gcs)
            yield finish_cli(proc), gcs, injected
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def reported_at(gcs: GroundStation, since: float, text: str) -> float:
    """When the vehicle said ``text`` (STATUSTEXT) after ``since``."""
    stamps = [t for t, _, said in gcs.seen.texts if t >= since and said == text]
    assert stamps, f"the vehicle never said {text!r}: {gcs.seen.texts}"
    return stamps[0]


def last_reported_before(gcs: GroundStation, end: float, text: str) -> float:
    """The last time the vehicle said ``text`` (STATUSTEXT) before ``end``."""
    stamps = [t for t, _, said in gcs.seen.texts if t <= end and said == text]
    assert stamps, f"the vehicle never said {text!r} before the action ended: {gcs.seen.texts}"
    return stamps[-1]


def assert_left_safe(gcs: GroundStation, modes: tuple[str, ...] = COPTER_SAFE) -> None:
    gcs.wait(lambda s: s.modes[-1][1] in modes, 20, f"one of {modes}")


def test_gps_lost(sitl: Sitl, tmp_path: Path) -> None:
    copter = sitl.start("copter", speedup=SPEEDUP)
    gps_off = lambda g: g.set_param("SIM_GPS_DISABLE", 1)  # noqa: E731
    with survey_with_fault(copter.gcs_url, copter.url, tmp_path, gps_off) as (
        report,
        gcs,
        injected,
    ):
        [(action, message, end)] = failed(report)
        assert not report["success"] and action.startswith("(fly uav1"), describe(report)
        # the first thing the vehicle says: 'EKF variance', 'EKF3 lane switch 1' (both
        # CRITICAL) or 'EKF Failsafe: changed to LAND Mode', depending on the run
        said = message.split("'")[1]
        assert end - reported_at(gcs, injected, said) <= REPORT_WITHIN, describe(report)
        assert_left_safe(gcs)


def test_battery_failsafe(sitl: Sitl, tmp_path: Path) -> None:
    # ArduPilot's autotest way: a low-voltage failsafe set to RTL, then the voltage drops
    params = {"BATT_LOW_VOLT": 11.5, "BATT_LOW_TIMER": 1, "BATT_FS_LOW_ACT": 2}
    copter = sitl.start("copter", speedup=SPEEDUP, params=params)
    low = lambda g: g.set_param("SIM_BATT_VOLTAGE", 11.0)  # noqa: E731
    with survey_with_fault(copter.gcs_url, copter.url, tmp_path, low, replans=1) as (
        report,
        gcs,
        injected,
    ):
        (action, message, end) = failed(report)[0]
        assert action == FIRST_LEG, describe(report)
        assert message == f"{copter.url}: failsafe: 'Battery Failsafe'", describe(report)
        assert end - reported_at(gcs, injected, "Battery Failsafe") <= REPORT_WITHIN
        # the replanned flight is refused: the failsafe keeps the copter until it lands
        assert not report["success"], describe(report)
        assert "is in failsafe ('Battery Failsafe')" in failed(report)[-1][1], describe(report)
        assert_left_safe(gcs, ("RTL", "LAND"))


def test_takeover_by_another_ground_station(sitl: Sitl, tmp_path: Path) -> None:
    copter = sitl.start("copter", speedup=SPEEDUP)
    takeover = lambda g: g.set_mode("LOITER")  # noqa: E731
    with survey_with_fault(copter.gcs_url, copter.url, tmp_path, takeover, replans=1) as (
        report,
        gcs,
        _,
    ):
        [(action, message, end)] = failed(report)
        assert action == FIRST_LEG, describe(report)
        assert message == f"{copter.url}: mode changed to LOITER by someone else (expected GUIDED)"
        loiter = next(t for t, m in gcs.seen.modes if m == "LOITER")
        assert end - loiter <= REPORT_WITHIN
        # the executor replans; the new plan takes GUIDED back and lands
        assert report["success"] and report["replans"] == 1, describe(report)
        assert_left_safe(gcs, ("LAND",))
        gcs.wait(lambda s: not s.armed[-1][1], 20, "disarmed")


def test_refused_arming(sitl: Sitl, tmp_path: Path) -> None:
    # a pre-arm check that keeps failing: the battery is below the arming voltage
    copter = sitl.start("copter", speedup=SPEEDUP, params={"BATT_ARM_VOLT": 13.0})
    with survey_with_fault(copter.gcs_url, copter.url, tmp_path, None) as (report, gcs, _):
        [(action, message, end)] = failed(report)
        assert action == "(takeoff uav1 pad)", describe(report)
        text = "Arm: Battery 1 below minimum arming voltage"
        assert message.endswith(text), describe(report)
        # the adapter tries again once (a refusal can be passing) and fails on the
        # repeat: the latency counts from the refusal it acted on
        assert end - last_reported_before(gcs, end, text) <= REPORT_WITHIN
        assert not report["success"]
        assert not gcs.armed


def test_link_dropped(sitl: Sitl, tmp_path: Path) -> None:
    # the vehicle's own GCS failsafe (RTL) brings it home when the adapter's link goes
    # (FS_GCS_TIMEOUT in simulated seconds: the adapter's 1 Hz heartbeat is 10 s apart
    # at speedup 10, more than the default 5 s)
    params = {"FS_GCS_ENABLE": 1, "FS_GCS_TIMEOUT": 20}
    copter = sitl.start("copter", speedup=SPEEDUP, params=params)
    relay = Relay(copter.url)
    try:
        cut = lambda g: relay.cut()  # noqa: E731
        with survey_with_fault(copter.gcs_url, relay.url, tmp_path, cut) as (report, gcs, injected):
            [(action, message, end)] = failed(report)
            assert action == FIRST_LEG, describe(report)
            assert message.startswith(f"{relay.url}: link closed"), describe(report)
            assert end - injected <= REPORT_WITHIN
            assert not report["success"]
            assert_left_safe(gcs, ("RTL", "LAND"))
    finally:
        relay.close()


def test_wind_stronger_than_the_copter(sitl: Sitl, tmp_path: Path) -> None:
    # 30 m/s from the north, against the first leg: ArduCopter stays in GUIDED, leans
    # as far as ANGLE_MAX lets it and drifts south without a word. The adapter sees it
    # in the vehicle's own positions: no headway for timeouts.stall s of vehicle time.
    copter = sitl.start("copter", speedup=SPEEDUP)

    def gale(gcs: GroundStation) -> None:
        gcs.set_param("SIM_WIND_DIR", 0)
        gcs.set_param("SIM_WIND_SPD", 30)

    with survey_with_fault(copter.gcs_url, copter.url, tmp_path, gale) as (report, gcs, _):
        [(action, message, end)] = failed(report)
        assert action == FIRST_LEG, describe(report)
        assert message.startswith(f"{copter.url}: no headway to north_field: "), describe(report)
        assert not report["success"], describe(report)
        # when the positions the vehicle sent (as the second ground station heard them)
        # first showed no headway for the stall window
        [leg] = [r for r in report["records"] if r["action"] == FIRST_LEG]
        north_field = offset(copter.home, 60, 10, 15)
        shown = gcs.stalled_at(north_field, Timeouts().stall, leg["start"])
        assert shown is not None, gcs.seen.track[-3:]
        assert end - shown <= REPORT_WITHIN, (end - shown, describe(report))
        assert_left_safe(gcs, ("LAND",))  # the default safe mode
