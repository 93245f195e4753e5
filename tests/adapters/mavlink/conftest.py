"""Fixtures for the MAVLink adapter tests: fast vehicle doubles, real SITL, no leaks.

The fleet mission at speedup 1 (checked by ``test_mavlink_sitl.py::
test_fleet_in_real_time``) mostly waits, about two minutes in real time. So this
folder's SITL tests run after its other tests, the fleet starts with the first of
them (the ``sitl`` fixture asks for it) and its check comes last: the other SITL tests
fly meanwhile, and the doubles' tests, timed in vehicle time at 40x, never share the
machine with it.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from mavlink_support import SPEEDUP
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from plansys_bridge_adapters.mavlink.sitl import missing, sitl_dir
from sitl_support import RealTimeFleet, Sitl

HERE = Path(__file__).parent
REAL_TIME_CHECK = "test_fleet_in_real_time"
"""The test that checks the real-time fleet (in test_mavlink_sitl.py)."""


def _is_real_time_check(item: pytest.Item) -> bool:
    return item.name == REAL_TIME_CHECK and item.path.parent == HERE


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """This folder's tests in their order, then its SITL tests (marked ``sitl``) in
    theirs, then the real-time fleet's check; the tests of other folders stay put."""
    mine = [i for i, item in enumerate(items) if HERE in item.path.parents]
    if not mine:
        return
    first, last = mine[0], mine[-1]
    folder = items[first : last + 1]
    doubles = [item for item in folder if item.get_closest_marker("sitl") is None]
    sitl = [item for item in folder if item.get_closest_marker("sitl") is not None]
    checks = [item for item in sitl if _is_real_time_check(item)]
    others = [item for item in sitl if not _is_real_time_check(item)]
    items[first : last + 1] = doubles + others + checks


@pytest.fixture(scope="session")
def fleet_in_real_time(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[RealTimeFleet]:
    """The fleet mission at speedup 1, started by the first SITL test when its check
    is selected (a failure to start it is raised by the check, not there)."""
    if any(_is_real_time_check(item) for item in request.session.items):
        fleet = RealTimeFleet.start(tmp_path_factory.mktemp("fleet_x1"))
    else:
        fleet = RealTimeFleet(skipped=f"{REAL_TIME_CHECK} not selected")
    try:
        yield fleet
    finally:
        fleet.close()


@pytest.fixture(autouse=True)
def _no_leaks(no_leaks: None) -> Iterator[None]:
    yield


@pytest.fixture
def copter() -> Iterator[VehicleDouble]:
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=4.0) as double:
        yield double


@pytest.fixture
def rover() -> Iterator[VehicleDouble]:
    with VehicleDouble("rover", speedup=SPEEDUP, ekf_delay=4.0) as double:
        yield double


@pytest.fixture
def sitl(tmp_path: Path, fleet_in_real_time: RealTimeFleet) -> Iterator[Sitl]:
    """ArduPilot SITL from ``$PLANSYS_BRIDGE_SITL_DIR``; the test is skipped without it.
    (The real-time fleet is asked for here only to start it with the first SITL test.)"""
    folder = sitl_dir()
    reason = missing(folder)
    if reason is not None:
        pytest.skip(reason)
    assert folder is not None
    launcher = Sitl(folder, tmp_path)
    try:
        yield launcher
    finally:
        launcher.stop_all()
