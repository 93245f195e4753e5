"""What ArduPilot's arming refusals say, and which of them waiting will cure.

A refused arm comes with ``PreArm: ...`` / ``Arm: ...`` STATUSTEXTs naming the
failing check. Reasons a vehicle gives while it is still starting up (no position
estimate, sensors settling) go away by themselves; any other (a battery below its
arming voltage, a failing check) does not, and the client stops retrying.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterable
from typing import Protocol

from plansys_bridge.retry import retrying

from .errors import CommandRefused
from .vehicle_state import ML, StatusText, Telemetry


class Armable(Protocol):
    """What arming needs of the vehicle client."""

    url: str
    telemetry: Telemetry

    @property
    def statustexts(self) -> Iterable[StatusText]: ...

    def _now(self) -> float: ...

    async def command(self, command: int, *params: float, retries: int | None = None) -> None: ...

    async def wait_for(self, predicate: Callable[[], bool], timeout: float, what: str) -> None: ...


ARMING_TEXT_PREFIXES = ("prearm:", "arm:")

STARTING_UP_WORDS = (
    "position estimate",
    "waiting",
    "initialising",
    "initializing",
    "settling",
    "calibrating",
    "ekf",
    "ahrs",
)
"""Arming refusals that a vehicle still starting up gives (retried, not final)."""


class RefusedForNow(CommandRefused):
    """An arming refusal worth another try: the vehicle may still be starting up."""

    def __init__(self, refusal: CommandRefused) -> None:
        self.refusal = refusal
        super().__init__(refusal.url, refusal.command, refusal.result, attempts=refusal.attempts)


def is_arming_text(text: str) -> bool:
    return text.lower().startswith(ARMING_TEXT_PREFIXES)


def starting_up(reason: str) -> bool:
    """``reason`` is one a vehicle still starting up gives (worth retrying)."""
    lowered = reason.lower()
    return any(word in lowered for word in STARTING_UP_WORDS)


def arming_texts(statustexts: Iterable[StatusText], since: float) -> str:
    """The last three distinct arming STATUSTEXTs heard at or after ``since``."""
    seen: list[str] = []
    for entry in statustexts:
        if is_arming_text(entry.text) and entry.stamp >= since and entry.text not in seen:
            seen.append(entry.text)
    return "; ".join(seen[-3:])


async def arm(vehicle: Armable, timeout: float, retry_period: float) -> None:
    """:meth:`MavlinkVehicle.arm <.vehicle.MavlinkVehicle.arm>`: try every
    ``retry_period`` seconds while the refusal may pass, for at most ``timeout``."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    start = vehicle._now()
    reasons: list[str] = []

    async def try_once() -> None:
        tried = vehicle._now()
        try:
            await vehicle.command(ML.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        except CommandRefused as exc:
            if exc.result not in ("MAV_RESULT_FAILED", "MAV_RESULT_TEMPORARILY_REJECTED"):
                raise
            reason = arming_texts(vehicle.statustexts, tried) or exc.reason
            if reason and reasons[-1:] == [reason] and not starting_up(reason):
                raise CommandRefused(vehicle.url, "arming", exc.result, reason) from exc
            reasons.append(reason)
            raise RefusedForNow(exc) from exc
        await vehicle.wait_for(
            lambda: vehicle.telemetry.armed,
            max(1.0, deadline - loop.time()),
            "a HEARTBEAT showing the vehicle armed",
        )

    try:
        async for attempt in retrying(every=retry_period, within=timeout, on=RefusedForNow):
            with attempt:
                if not vehicle.telemetry.armed:
                    await try_once()
    except RefusedForNow as exc:
        why = arming_texts(vehicle.statustexts, start) or exc.refusal.reason
        raise CommandRefused(
            vehicle.url, "arming", exc.result, f"still refused after {timeout:g} s: {why}"
        ) from exc.refusal
