"""The shipped missions against real ArduPilot SITL, through ``plansys-bridge run``.

Each test starts its own SITL instances (fresh working directory, wiped eeprom) from
``$PLANSYS_BRIDGE_SITL_DIR`` and is skipped, naming the variable, without it. The
missions are the shipped files with ``url:`` pointing at SITL; every one must end
SUCCEEDED with no action failed or halted, and the vehicles landed (copter, LAND,
disarmed) or held (rover, HOLD, disarmed), as a second ground station sees them.
Every mission runs at speedup 10; the fleet also at speedup 1 (real time), started
with the folder's first SITL test and checked after its last (conftest.py), so the
other SITL tests fly while it waits.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from plansys_bridge_adapters.mavlink.geo import GeoPoint
from plansys_bridge_adapters.mavlink.modes import Model
from plansys_bridge_adapters.mavlink.sitl import SitlProcess
from sitl_support import (
    ROVER_HOME,
    GroundStation,
    RealTimeFleet,
    Sitl,
    assert_succeeded,
    finish_cli,
    run_cli,
    sitl_mission,
    start_cli,
)

pytestmark = pytest.mark.sitl

SPEEDUP = 10.0


def check_fleet(copter: SitlProcess, rover: SitlProcess, proc: subprocess.Popen[str]) -> None:
    """The fleet mission succeeded, each vehicle did its own actions and is parked."""
    with GroundStation(copter.gcs_url, "copter") as air, GroundStation(rover.gcs_url) as ground:
        report = finish_cli(proc)
        assert_succeeded(report)
        by = {r["action"]: r["performer"] for r in report["records"]}
        assert all(p == "uav1_performer" for a, p in by.items() if " uav1 " in a)
        assert all(p == "ugv1_performer" for a, p in by.items() if " ugv1 " in a)
        assert {a.split()[0] for a in by} == {"(takeoff", "(fly", "(land", "(drive"}
        assert_parked(air, "LAND")
        assert_parked(ground, "HOLD")


def assert_parked(gcs: GroundStation, mode: str) -> None:
    """The vehicle ends disarmed in ``mode`` (seen in its HEARTBEAT)."""
    gcs.wait(lambda s: bool(s.modes) and s.modes[-1][1] == mode, 10, f"mode {mode}")
    gcs.wait(lambda s: bool(s.armed) and not s.armed[-1][1], 10, "disarmed")


def test_copter_survey_with_a_second_ground_station(sitl: Sitl, tmp_path: Path) -> None:
    copter = sitl.start("copter", speedup=SPEEDUP)
    mission = sitl_mission("mavlink_copter.yaml", {"uav1": copter.url}, tmp_path)
    proc = start_cli(mission)  # SITL opens its other ports once the adapter connects
    with GroundStation(copter.gcs_url, "copter") as gcs:
        gcs.stream("GLOBAL_POSITION_INT", 4)
        # the second ground station sees the flight and reads parameters during it
        gcs.wait(lambda s: s.max_alt > 5, 120, "the copter to climb")
        speed = gcs.param("WPNAV_SPEED")
        sysid = gcs.param("SYSID_THISMAV")
        report = finish_cli(proc)
        assert_succeeded(report)
        kinds = [r["action"].split()[0] for r in report["records"]]
        assert kinds[0] == "(takeoff" and kinds[-1] == "(land" and "(fly" in kinds
        assert_parked(gcs, "LAND")
        modes = [m for _, m in gcs.seen.modes]
        assert "GUIDED" in modes and modes[-1] == "LAND"
        assert gcs.seen.max_alt > 14  # north_field is at 15 m
        assert gcs.seen.north_max > 55  # north_field is 60 m north of the pad
    assert speed > 0 and sysid == 1


def test_rover_patrol(sitl: Sitl, tmp_path: Path) -> None:
    rover = sitl.start("rover", speedup=SPEEDUP)
    mission = sitl_mission("mavlink_rover.yaml", {"ugv1": rover.url}, tmp_path)
    proc = start_cli(mission)
    with GroundStation(rover.gcs_url, "rover") as gcs:
        report = finish_cli(proc)
        assert_succeeded(report)
        assert [r["action"].split()[0] for r in report["records"]] == ["(drive"] * 4
        assert_parked(gcs, "HOLD")


def test_fleet_ten_times_faster(sitl: Sitl, tmp_path: Path) -> None:
    copter = sitl.start("copter", speedup=SPEEDUP)
    rover = sitl.start("rover", speedup=SPEEDUP, home=ROVER_HOME)
    urls = {"uav1": copter.url, "ugv1": rover.url}
    proc = start_cli(sitl_mission("mavlink_fleet.yaml", urls, tmp_path))
    check_fleet(copter, rover, proc)


def test_nearest_vehicle_wins_each_visit(sitl: Sitl, tmp_path: Path) -> None:
    homes: dict[str, tuple[Model, GeoPoint]] = {
        "uav1": ("copter", GeoPoint(-35.363261, 149.165230, 584.0)),
        "uav2": ("copter", GeoPoint(-35.363261, 149.166332, 584.0)),
        "ugv1": ("rover", GeoPoint(-35.362363, 149.165230, 584.0)),
    }
    started = {v: sitl.start(m, speedup=SPEEDUP, home=h) for v, (m, h) in homes.items()}
    mission = sitl_mission("mavlink_nearest.yaml", {v: s.url for v, s in started.items()}, tmp_path)
    report = run_cli(mission)
    assert_succeeded(report)
    visits = {r["action"]: r["performer"] for r in report["records"] if "visit" in r["action"]}
    assert visits == {
        "(visit tower)": "uav1_performer",
        "(visit orchard)": "uav2_performer",
        "(visit gate)": "ugv1_performer",
    }
    for vehicle, proc in started.items():
        with GroundStation(proc.gcs_url, homes[vehicle][0]) as gcs:
            assert_parked(gcs, "LAND" if homes[vehicle][0] == "copter" else "HOLD")


def test_fleet_in_real_time(fleet_in_real_time: RealTimeFleet) -> None:
    # moved after the folder's last test by conftest.py: the mission started with the
    # folder's first SITL test, at speedup 1
    if fleet_in_real_time.skipped is not None:
        pytest.skip(fleet_in_real_time.skipped)
    try:
        check_fleet(*fleet_in_real_time.started())
    finally:
        fleet_in_real_time.close()
