"""Fault supervision of a running action: what the vehicle does that ends it.

While an action runs under :meth:`VehicleSupervision.supervise`, each of these
becomes the exception that ends it: a failsafe (its STATUSTEXT), a mode nobody asked
for (someone else took the vehicle: RC, another ground station), a HEARTBEAT whose
system state turns CRITICAL or EMERGENCY (ArduPilot's sign that a failsafe holds), a
STATUSTEXT of severity ERROR or worse, a disarm while the action needs the vehicle armed, a silent
link (no HEARTBEAT) and a closed link. A mode change ArduPilot makes on its own while
it boots is a fallback, not a takeover, and is only counted.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections import deque
from collections.abc import Awaitable
from typing import Any, TypeVar

from .arming import is_arming_text
from .errors import LinkError, MavlinkError, VehicleFault
from .link import LinkSettings
from .modes import Model, mode_name
from .vehicle_state import ML, StatusText, Telemetry

log = logging.getLogger(__name__)
T = TypeVar("T")

EXPLAIN_WAIT = 0.3
"""Seconds a mode change nobody asked for, or a system state turning CRITICAL, waits
for the STATUSTEXT explaining it."""

DISTRESS = {ML.MAV_STATE_CRITICAL: "CRITICAL", ML.MAV_STATE_EMERGENCY: "EMERGENCY"}
"""HEARTBEAT system_status values that mean the vehicle is in a failsafe."""


class VehicleSupervision:
    """The fault side of :class:`~.vehicle.MavlinkVehicle` (its base class)."""

    url: str
    settings: LinkSettings
    telemetry: Telemetry
    model: Model | None
    statustexts: deque[StatusText]
    _loop: asyncio.AbstractEventLoop | None
    _link_error: str | None

    def _init_supervision(self) -> None:
        self.expected_modes: frozenset[int] = frozenset()
        """While supervised: modes the action accepts; any other mode is a fault."""
        self.expect_armed = False
        """While supervised: a disarm is a fault (a copter must not disarm mid-air)."""
        self._fault: asyncio.Future[MavlinkError] | None = None
        self._pending_mode: tuple[int, int] | None = None
        self.boot_fallbacks = 0
        """Mode changes ArduPilot made on its own while booting (not takeovers)."""
        self.in_control = True
        """False once a failsafe or someone else took the vehicle, until we set a mode."""
        self.failsafe: str | None = None
        """The vehicle's failsafe STATUSTEXT while that failsafe holds (until disarmed)."""
        self._unexplained_mode: int | None = None

    def _now(self) -> float:
        loop = self._loop
        return loop.time() if loop is not None else time.monotonic()

    def mode_name_of(self, number: int) -> str:
        return mode_name(self.model or "copter", number)

    def booting(self) -> bool:
        """Disarmed and without a position estimate yet: ArduPilot may still change
        its mode on its own (boot-time fallback), so modes set now do not stick."""
        return not self.telemetry.armed and not self.telemetry.ekf_ready()

    # ------------------------------------------------------------ what it hears
    def _check_heartbeat(self, was_armed: bool, was_status: int | None = None) -> None:
        tel = self.telemetry
        if tel.custom_mode is not None:
            self._check_mode(tel.custom_mode)
        state = tel.system_status
        loop, fault = self._loop, self._fault
        if state in DISTRESS and state != was_status and fault is not None and loop is not None:
            # ArduPilot reports CRITICAL as a failsafe triggers and may send the
            # HEARTBEAT before the STATUSTEXT naming it: give that a moment to arrive
            loop.call_later(EXPLAIN_WAIT, self._distress_fault, fault)
        if was_armed and not tel.armed:
            self.failsafe = None  # landed and disarmed: a new flight may start
        if was_armed and not tel.armed and self.expect_armed:
            self._raise_fault(VehicleFault(self.url, f"disarmed unexpectedly{self._recent_note()}"))

    def _check_mode(self, mode: int) -> None:
        pending = self._pending_mode
        if pending is not None:
            old, new = pending
            if mode == new:
                self._pending_mode = None
            elif mode == old:
                return  # the mode change we asked for is not visible yet
        if not self.expected_modes or mode in self.expected_modes:
            return
        name = self.mode_name_of(mode)
        if self.booting():
            # ArduPilot accepts a mode while it boots, then sets its initial mode when
            # boot completes (copter: INITIAL_MODE at "ArduPilot Ready"; rover: the RC
            # mode channel once RC input arrives). Nobody took the vehicle over.
            log.info("%s: mode fell back to %s while the vehicle booted", self.url, name)
            self.boot_fallbacks += 1
            return
        if self._unexplained_mode is None and self._loop is not None:
            # ArduPilot queues the STATUSTEXT that explains a mode change ("Battery
            # Failsafe") and may send the HEARTBEAT first: give it a moment to arrive.
            self._unexplained_mode = mode
            self._loop.call_later(EXPLAIN_WAIT, self._mode_fault)

    def _mode_fault(self) -> None:
        mode, self._unexplained_mode = self._unexplained_mode, None
        current = self.telemetry.custom_mode
        if mode is None or current is None or not self.expected_modes:
            return
        if current in self.expected_modes:
            return
        name = self.mode_name_of(current)
        expected = "/".join(sorted(self.mode_name_of(m) for m in self.expected_modes))
        failsafe = self._recent_failsafe()
        if failsafe is not None:
            text = f"failsafe: {failsafe.text!r}, mode now {name}"
        else:
            text = f"mode changed to {name} by someone else (expected {expected})"
        self._raise_fault(VehicleFault(self.url, text, took_over=True))

    def _distress_fault(self, fault: asyncio.Future[MavlinkError]) -> None:
        """The system state turned CRITICAL/EMERGENCY during the action ``fault`` belongs
        to (one already in distress when it began is the action's starting point)."""
        state = DISTRESS.get(self.telemetry.system_status or 0)
        if state is None or fault is not self._fault:
            return  # cleared meanwhile, or that action is over
        failsafe = self._recent_failsafe()
        note = f", failsafe: {failsafe.text!r}" if failsafe is not None else self._recent_note()
        self._raise_fault(
            VehicleFault(self.url, f"vehicle state {state} (HEARTBEAT){note}", took_over=True)
        )

    def _check_statustext(self, entry: StatusText) -> None:
        lowered = entry.text.lower()
        if is_arming_text(entry.text):
            return  # arming checks explain refusals; arm() reports them
        if "failsafe" in lowered and "cleared" in lowered:
            self.failsafe = None
        elif "failsafe" in lowered:
            self.failsafe = entry.text
            self._raise_fault(VehicleFault(self.url, f"failsafe: {entry.text!r}", took_over=True))
        elif entry.severity <= ML.MAV_SEVERITY_ERROR:
            self._raise_fault(
                VehicleFault(self.url, f"vehicle reported {entry.severity_name}: {entry.text!r}")
            )

    # ------------------------------------------------------------- faults
    def _raise_fault(self, error: MavlinkError) -> None:
        if isinstance(error, VehicleFault) and error.took_over:
            self.in_control = False
        fault = self._fault
        if fault is not None and not fault.done():
            fault.set_result(error)

    def _recent_failsafe(self, within: float = 5.0) -> StatusText | None:
        now = self._now()
        for entry in reversed(self.statustexts):
            if now - entry.stamp > within:
                break
            if "failsafe" in entry.text.lower():
                return entry
        return None

    def _recent_note(self, within: float = 3.0) -> str:
        now = self._now()
        recent = [e.text for e in self.statustexts if now - e.stamp <= within]
        return f" (vehicle said: {'; '.join(recent[-3:])})" if recent else ""

    async def supervise(self, work: Awaitable[T]) -> T:
        """Run ``work``; raise the first fault the vehicle shows while it runs.

        Faults: failsafe, mode not in :attr:`expected_modes`, system state CRITICAL
        or EMERGENCY, STATUSTEXT with severity ERROR or worse, disarm while
        :attr:`expect_armed`, no HEARTBEAT for ``heartbeat_timeout``, link closed.
        """
        loop = asyncio.get_running_loop()
        task: asyncio.Future[T] = asyncio.ensure_future(work)
        fault: asyncio.Future[MavlinkError] = loop.create_future()
        self._fault = fault
        if self._link_error is not None:
            fault.set_result(LinkError(self.url, self._link_error))
        try:
            waiting: set[asyncio.Future[Any]] = {task, fault}
            await asyncio.wait(waiting, return_when=asyncio.FIRST_COMPLETED)
            if task.done():
                return task.result()
            raise fault.result()
        finally:
            if self._fault is fault:
                self._fault = None
            if not task.done():
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await task

    async def _watchdog(self) -> None:
        limit = self.settings.heartbeat_timeout
        while True:
            await asyncio.sleep(min(0.1, limit / 4))
            silent = self._now() - self.telemetry.last_heartbeat
            if silent > limit and self._fault is not None:
                self._raise_fault(
                    LinkError(self.url, f"no HEARTBEAT for {silent:.1f} s (limit {limit:g} s)")
                )
