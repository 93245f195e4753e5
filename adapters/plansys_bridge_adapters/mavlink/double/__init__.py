"""A MAVLink vehicle double: an ArduCopter / ArduRover look-alike on a loopback socket.

In-process use (tests)::

    with VehicleDouble("copter", speedup=20) as double:
        vehicle = MavlinkVehicle(double.url)
        ...
        double.failsafe()

Command line: ``python -m plansys_bridge_adapters.mavlink.double --model copter --port 5760``.
"""

from __future__ import annotations

from .server import VehicleDouble
from .sim import SimParams, VehicleSim

__all__ = ["SimParams", "VehicleDouble", "VehicleSim"]
