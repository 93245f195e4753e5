"""Fixtures for the MAVLink adapter tests: fast vehicle doubles, real SITL, no leaks."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from mavlink_support import SPEEDUP
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from plansys_bridge_adapters.mavlink.sitl import missing, sitl_dir
from sitl_support import Sitl


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
def sitl(tmp_path: Path) -> Iterator[Sitl]:
    """ArduPilot SITL from ``$PLANSYS_BRIDGE_SITL_DIR``; the test is skipped without it."""
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
