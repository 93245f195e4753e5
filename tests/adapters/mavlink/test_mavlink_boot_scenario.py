"""One scenario from a fresh boot, run against the vehicle double and real SITL.

The scenario does what a careless ground station does: set GUIDED the moment the
first HEARTBEAT arrives, try to arm at once, then wait for the EKF, set GUIDED
again, arm, move and stop. It records the modes (from HEARTBEAT), the COMMAND_ACK
results and the armed states in order. The double must give the sequence that
ArduPilot SITL gives (recorded below from ArduCopter/ArduRover 4.6 SITL, and
compared live with SITL when ``$PLANSYS_BRIDGE_SITL_DIR`` is set).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from typing import Any

import pytest
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from plansys_bridge_adapters.mavlink.errors import CommandRefused
from plansys_bridge_adapters.mavlink.geo import offset
from plansys_bridge_adapters.mavlink.modes import Model
from plansys_bridge_adapters.mavlink.vehicle import (
    DEFAULT_TELEMETRY_HZ,
    LinkSettings,
    MavlinkVehicle,
)
from pymavlink.dialects.v20 import ardupilotmega as ml
from sitl_support import GroundStation, Sitl

Event = tuple[str, str]

SCENARIO_COMMANDS = {
    ml.MAV_CMD_DO_SET_MODE: "set_mode",
    ml.MAV_CMD_COMPONENT_ARM_DISARM: "arm_disarm",
    ml.MAV_CMD_NAV_TAKEOFF: "takeoff",
}

EXPECTED: dict[Model, list[Event]] = {
    "copter": [
        ("mode", "STABILIZE"),
        ("armed", "False"),
        ("ack", "set_mode ACCEPTED"),
        ("mode", "GUIDED"),
        ("mode", "STABILIZE"),  # "ArduPilot Ready": boot ends in the initial mode
        ("ack", "arm_disarm FAILED"),  # no position estimate yet
        ("ack", "set_mode ACCEPTED"),
        ("mode", "GUIDED"),
        ("ack", "arm_disarm ACCEPTED"),
        ("armed", "True"),
        ("ack", "takeoff ACCEPTED"),
        ("ack", "set_mode ACCEPTED"),
        ("mode", "LAND"),
        ("armed", "False"),
    ],
    "rover": [
        ("mode", "INITIALISING"),
        ("armed", "False"),
        ("ack", "set_mode ACCEPTED"),
        ("mode", "GUIDED"),
        ("mode", "MANUAL"),  # "ArduPilot Ready", and RC 8 (the mode channel) says MANUAL
        ("ack", "arm_disarm FAILED"),  # no position estimate yet
        ("ack", "set_mode ACCEPTED"),
        ("mode", "GUIDED"),
        ("ack", "arm_disarm ACCEPTED"),
        ("armed", "True"),
        ("ack", "set_mode ACCEPTED"),
        ("mode", "HOLD"),
        ("ack", "arm_disarm ACCEPTED"),
        ("armed", "False"),
    ],
}


def recorder(vehicle: MavlinkVehicle, events: list[Event]) -> None:
    def on_message(msg: Any) -> None:
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            mode = vehicle.mode_name_of(int(msg.custom_mode))
            armed = str(bool(msg.base_mode & ml.MAV_MODE_FLAG_SAFETY_ARMED))
            for name, value in (("mode", mode), ("armed", armed)):
                if next((v for k, v in reversed(events) if k == name), None) != value:
                    events.append((name, value))
        elif kind == "COMMAND_ACK" and msg.command in SCENARIO_COMMANDS:
            result = ml.enums["MAV_RESULT"][msg.result].name.removeprefix("MAV_RESULT_")
            events.append(("ack", f"{SCENARIO_COMMANDS[msg.command]} {result}"))

    vehicle.add_listener(on_message)


async def scenario(
    url: str, model: Model, wall_timeout: float, after_boot: Callable[[], None]
) -> list[Event]:
    """The scenario on the vehicle at ``url`` (its clock not started yet);
    ``after_boot()`` runs once boot is over (to speed the vehicle up)."""
    events: list[Event] = []
    vehicle = MavlinkVehicle(url, LinkSettings(telemetry_hz={}, command_timeout=2.0))
    recorder(vehicle, events)
    await vehicle.connect()  # the first HEARTBEAT; no telemetry asked for yet
    try:
        await vehicle.command(ml.MAV_CMD_DO_SET_MODE, 1, vehicle.mode_number("GUIDED"))
        await vehicle.wait_for(lambda: vehicle.mode == "GUIDED", 5, "GUIDED")
        await vehicle.request_telemetry(DEFAULT_TELEMETRY_HZ)
        initial = "STABILIZE" if model == "copter" else "MANUAL"
        await vehicle.wait_for(lambda: vehicle.mode == initial, wall_timeout, "the fallback")
        after_boot()
        with pytest.raises(CommandRefused):
            await vehicle.command(ml.MAV_CMD_COMPONENT_ARM_DISARM, 1, retries=1)
        await vehicle.wait_ekf(wall_timeout)
        await vehicle.set_mode("GUIDED")
        await vehicle.arm(wall_timeout)
        if model == "copter":
            await vehicle.takeoff(5.0)
            await vehicle.wait_for(
                lambda: (vehicle.telemetry.position or offset_home(vehicle)).alt > 4.0,
                wall_timeout,
                "5 m",
            )
            await vehicle.set_mode("LAND")
        else:
            start = await vehicle.wait_position(5)
            vehicle.send_position_target(offset(start, 15.0, 0.0))
            await vehicle.wait_for(lambda: moved(vehicle, start) > 10.0, wall_timeout, "10 m")
            await vehicle.set_mode("HOLD")
            await vehicle.wait_for(lambda: vehicle.telemetry.velocity[0] < 0.2, 30, "a stop")
            await vehicle.disarm()
        await vehicle.wait_for(lambda: not vehicle.telemetry.armed, wall_timeout, "disarmed")
        await asyncio.sleep(0.3)
    finally:
        await vehicle.close()
    return events


def offset_home(vehicle: MavlinkVehicle) -> Any:
    assert vehicle.telemetry.home is not None
    return vehicle.telemetry.home


def moved(vehicle: MavlinkVehicle, start: Any) -> float:
    from plansys_bridge_adapters.mavlink.geo import distance_m

    here = vehicle.telemetry.position
    return 0.0 if here is None else distance_m(start, here)


@pytest.mark.parametrize("model", ["copter", "rover"])
def test_the_double_boots_as_sitl_does(model: Model) -> None:
    # real time while booting: the GUIDED sent at the first HEARTBEAT lands before
    # "ArduPilot Ready"; then 20x
    with VehicleDouble(model, speedup=1.0) as double:

        def faster() -> None:
            double.speedup = 20.0

        events = asyncio.run(scenario(double.url, model, 60, faster))
    assert events == EXPECTED[model]


@pytest.mark.sitl
@pytest.mark.parametrize("model", ["copter", "rover"])
def test_sitl_boots_as_the_double_does(sitl: Sitl, model: Model) -> None:
    # real time while booting (as for the double), then 10x through SIM_SPEEDUP
    vehicle = sitl.start(model, speedup=1.0)
    with contextlib.ExitStack() as stack:

        def faster() -> None:  # SITL opens SERIAL1 once the first client is there
            gcs = stack.enter_context(GroundStation(vehicle.gcs_url, model))
            gcs.set_param("SIM_SPEEDUP", 10)

        events = asyncio.run(scenario(vehicle.url, model, 120, faster))
    assert events == EXPECTED[model]
