"""Fixtures for the MAVLink adapter tests: fast vehicle doubles, no leaks."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from mavlink_support import SPEEDUP
from plansys_bridge_adapters.mavlink.double import VehicleDouble


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
