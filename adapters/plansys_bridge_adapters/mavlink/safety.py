"""Leaving a vehicle safe: after a failed or cancelled action, when the link comes
back after it was lost, and when its performer stops (mission end, abort, Ctrl-C or
SIGTERM of ``plansys-bridge run``).

The safe mode is the performer's ``safe_mode`` (copter LAND by default, or RTL,
SMART_RTL, BRAKE, LOITER; rover HOLD, ...). A copter lands by default because
whatever stops the adapter may also keep it from coming back (SIGTERM, an abort, a
lost link): a hovering copter would stay up until its battery failsafe.

The rule: the adapter only makes safe a vehicle it still controls, that is one in
GUIDED, the mode the adapter flies in. A vehicle that changed mode on its own (a
failsafe: RTL, LAND, HOLD) or was taken over by a pilot or another ground station
is left alone: ArduPilot or that person already decided, and switching modes back would fight them.
"""

from __future__ import annotations

import asyncio
import logging

from .errors import MavlinkError
from .modes import Model
from .vehicle import MavlinkVehicle

log = logging.getLogger(__name__)

SAFE_MODES: dict[Model, tuple[str, ...]] = {
    "copter": ("LAND", "RTL", "SMART_RTL", "BRAKE", "LOITER"),
    "rover": ("HOLD", "RTL", "LOITER", "SMART_RTL"),
}
"""Modes ``safe_mode`` may name, the first being the default."""
PUTS_DOWN = frozenset({"LAND", "RTL", "SMART_RTL"})
"""Copter safe modes that end on the ground: a later flight has to take off again."""
FRESH_HEARTBEAT = 1.2
"""Seconds to wait for a HEARTBEAT after a failure (ArduPilot sends one a second)."""
SAFE_TIMEOUT = 1.5
"""Seconds one safe-mode switch may take; the action's failure is reported after it."""


def safe_mode_for(model: Model | None, configured: str | None) -> str:
    """The configured safe mode if it suits ``model``, else the model's default."""
    modes = SAFE_MODES[model or "copter"]
    return configured if configured in modes else modes[0]


async def make_safe(vehicle: MavlinkVehicle, configured: str | None) -> str | None:
    """Switch an armed vehicle still in GUIDED to its safe mode; returns the mode set.

    Decided on a HEARTBEAT newer than the failure (the vehicle may have switched mode
    itself a moment ago) and bounded by :data:`SAFE_TIMEOUT`, so a failure is
    reported promptly even when the vehicle does not answer.
    """
    if not vehicle.connected:
        return None
    since = asyncio.get_running_loop().time()
    try:
        await vehicle.wait_for(
            lambda: vehicle.telemetry.last_heartbeat >= since, FRESH_HEARTBEAT, "a HEARTBEAT"
        )
    except MavlinkError:
        log.warning(
            "%s: no HEARTBEAT: cannot switch the vehicle to %s (its own failsafe decides)",
            vehicle.url,
            safe_mode_for(vehicle.model, configured),
        )
        return None
    if not vehicle.telemetry.armed or vehicle.mode != "GUIDED":
        return None
    if not vehicle.in_control:
        return None  # a failsafe or someone else has it (its HEARTBEAT may lag)
    mode = safe_mode_for(vehicle.model, configured)
    vehicle.expected_modes = frozenset()
    try:
        async with asyncio.timeout(SAFE_TIMEOUT):
            await vehicle.set_mode(mode, timeout=SAFE_TIMEOUT)
    except (MavlinkError, TimeoutError) as exc:
        log.warning("%s: could not switch to %s after a failure: %s", vehicle.url, mode, exc)
        return None
    finally:
        vehicle.expected_modes = frozenset()
    return mode


async def make_safe_when_heard(
    vehicle: MavlinkVehicle, configured: str | None, within: float
) -> str | None:
    """After the link was lost: wait up to ``within`` seconds for the vehicle to be
    heard again, then make it safe (if it is still in GUIDED: ArduPilot's own GCS
    failsafe may have taken it meanwhile, and then it is left alone)."""
    since = asyncio.get_running_loop().time()
    try:
        await vehicle.wait_for(
            lambda: vehicle.telemetry.last_heartbeat > since, within, "the link to come back"
        )
    except MavlinkError:
        return None
    mode = await make_safe(vehicle, configured)
    if mode is not None:
        log.warning("%s: link back; vehicle switched to %s", vehicle.url, mode)
    return mode


async def stop_safely(vehicle: MavlinkVehicle, configured: str | None, disarm: bool) -> None:
    """At the end: a vehicle in GUIDED is put in its safe mode (a rover stops in
    HOLD), and one on the ground is disarmed when ``disarm`` says so."""
    await make_safe(vehicle, configured)
    if not disarm or not vehicle.connected or not vehicle.telemetry.armed:
        return
    position = vehicle.telemetry.position
    airborne = vehicle.model == "copter" and (position is None or position.alt > 0.5)
    if airborne:
        return
    try:
        async with asyncio.timeout(SAFE_TIMEOUT * 2):
            await vehicle.disarm()
    except (MavlinkError, TimeoutError) as exc:
        log.warning("%s: could not disarm at the end: %s", vehicle.url, exc)
