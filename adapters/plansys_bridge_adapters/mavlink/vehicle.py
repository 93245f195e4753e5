"""An asyncio client for one ArduPilot vehicle over any pymavlink connection string.

The link's reader thread (:mod:`.link`) hands each message to the event loop;
everything else (the telemetry cache in :mod:`.vehicle_state`, COMMAND_ACK matching,
fault detection in :mod:`.supervision`, waiting) runs on the loop, so a performer
awaits vehicle operations like any other coroutine and cancellation just works.

What ArduPilot needs from a ground station, and this client does:

* wait for a HEARTBEAT from an autopilot before anything else;
* request the telemetry it relies on with MAV_CMD_SET_MESSAGE_INTERVAL (ArduPilot
  sends only HEARTBEAT and STATUSTEXT unasked);
* send its own GCS HEARTBEAT at 1 Hz (ArduPilot's GCS failsafe watches it);
* retry a command whose COMMAND_ACK does not come, and turn a refusal into
  :class:`CommandRefused` quoting the STATUSTEXT that explained it;
* while an action runs (:meth:`MavlinkVehicle.supervise`), turn a failsafe, a mode
  changed by someone else, a STATUSTEXT error, an unexpected disarm, a lost
  heartbeat or a closed link into an exception that ends the action.

Times here are loop time (``loop.time()``): on hardware that is the wall clock.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections import deque
from collections.abc import Callable, Mapping
from typing import Any

from .arming import arm
from .errors import CommandRefused, CommandTimeout, LinkError, MavlinkError, WaitTimeout
from .geo import GeoPoint
from .link import DEFAULT_TELEMETRY_HZ, LinkSettings, MavlinkLink
from .modes import MAV_AUTOPILOT_ARDUPILOTMEGA, Model, mode_number, model_of_type
from .supervision import VehicleSupervision
from .vehicle_state import ML, StatusText, Telemetry, enum_name, statustext_of

__all__ = ["DEFAULT_TELEMETRY_HZ", "LinkSettings", "MavlinkVehicle", "StatusText", "Telemetry"]

log = logging.getLogger(__name__)

MAV_TYPE_GCS = 6
MAV_AUTOPILOT_INVALID = 8
POSITION_ONLY_MASK = 0b0000_1101_1111_1000
"""SET_POSITION_TARGET_*: use x/y/z, ignore velocity, acceleration, yaw and yaw rate."""
LIFT_OFF_M = 0.5
"""Climb above the take-off altitude that shows a take-off is under way."""


class MavlinkVehicle(VehicleSupervision):
    """One vehicle behind one MAVLink link (``url`` in pymavlink's syntax)."""

    def __init__(self, url: str, settings: LinkSettings | None = None) -> None:
        self.url = url
        self.settings = settings or LinkSettings()
        self.telemetry = Telemetry()
        self.model: Model | None = None
        self.target_system = 0
        self.target_component = 0
        self.statustexts: deque[StatusText] = deque(maxlen=100)
        self._link = MavlinkLink(url, self.settings)
        self._loop: asyncio.AbstractEventLoop | None = None
        self._acks: dict[int, asyncio.Future[int]] = {}
        self._waiters: set[asyncio.Future[None]] = set()
        self._link_error: str | None = None
        self._tasks: list[asyncio.Task[None]] = []
        self._listeners: list[Callable[[Any], None]] = []
        self._connected = False
        self._closed_by_us = False
        self._init_supervision()

    # ------------------------------------------------------------ connection
    @property
    def connected(self) -> bool:
        return self._connected and self._link_error is None

    async def connect(self) -> None:
        """Open the link, wait for the autopilot's HEARTBEAT, request telemetry."""
        if self._connected:
            return
        self._loop = asyncio.get_running_loop()
        loop = self._loop
        deadline = loop.time() + self.settings.connect_timeout
        await self._link.open(deadline)
        self._closed_by_us = False
        self._link_error = None
        self._link.start_reading(self._on_message, self._on_link_error)
        # Our heartbeat first: over udpout the vehicle learns our address from it.
        self._tasks.append(loop.create_task(self._gcs_heartbeat(), name=f"gcs-hb {self.url}"))
        try:
            await self.wait_for(
                lambda: self.target_system != 0,
                max(0.0, deadline - loop.time()),
                "a HEARTBEAT from an autopilot",
            )
        except MavlinkError:
            await self.close()
            raise
        self._connected = True
        self._tasks.append(loop.create_task(self._watchdog(), name=f"watchdog {self.url}"))
        try:
            await self.request_telemetry(self.settings.telemetry_hz)
        except MavlinkError:
            await self.close()
            raise

    async def close(self) -> None:
        """Stop the reader thread and close the link (idempotent)."""
        self._connected = False
        self._closed_by_us = True
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        self._tasks.clear()
        await self._link.close()
        for fut in self._acks.values():
            if not fut.done():
                fut.cancel()
        self._acks.clear()
        self._wake()

    # ------------------------------------------------------------- loop side
    def receive(self, msg: Any) -> None:
        """Handle a message that came from elsewhere than the link (a replayed log)
        exactly as a received one: telemetry, fault checks, listeners."""
        if self._loop is None:
            self._loop = asyncio.get_running_loop()
        self._on_message(msg)

    def add_listener(self, callback: Callable[[Any], None]) -> Callable[[], None]:
        """Call ``callback(msg)`` for every message of this vehicle; returns remove."""
        self._listeners.append(callback)
        return lambda: self._listeners.remove(callback) if callback in self._listeners else None

    def _on_link_error(self, reason: str) -> None:
        if self._link_error is None and not self._closed_by_us:
            self._link_error = reason
            self._raise_fault(LinkError(self.url, reason))
        self._wake()

    def _on_message(self, msg: Any) -> None:
        kind = msg.get_type()
        src_sys, src_comp = msg.get_srcSystem(), msg.get_srcComponent()
        if self.target_system == 0:
            if (
                kind == "HEARTBEAT"
                and msg.type != MAV_TYPE_GCS
                and msg.autopilot != MAV_AUTOPILOT_INVALID
            ):
                self.target_system, self.target_component = src_sys, src_comp
                self.model = model_of_type(msg.type)
                if msg.autopilot != MAV_AUTOPILOT_ARDUPILOTMEGA:
                    log.warning("%s: autopilot %s is not ArduPilot", self.url, msg.autopilot)
            else:
                return
        if src_sys != self.target_system:
            return
        handler = _HANDLERS.get(kind)
        if handler is not None:
            handler(self, msg)
        for listener in list(self._listeners):
            try:
                listener(msg)
            except Exception:
                log.exception("%s: telemetry listener failed", self.url)
        self._wake()

    def _on_heartbeat(self, msg: Any) -> None:
        if msg.get_srcComponent() != self.target_component:
            return
        was_armed, was_status = self.telemetry.armed, self.telemetry.system_status
        self.telemetry.read_heartbeat(msg, self._now())
        self._check_heartbeat(was_armed, was_status)

    def _on_ack(self, msg: Any) -> None:
        fut = self._acks.get(int(msg.command))
        if fut is not None and not fut.done() and msg.result != ML.MAV_RESULT_IN_PROGRESS:
            fut.set_result(int(msg.result))

    def _on_statustext(self, msg: Any) -> None:
        entry = statustext_of(msg, self._now())
        self.statustexts.append(entry)
        log.info("%s: STATUSTEXT %s %s", self.url, entry.severity_name, entry.text)
        self._check_statustext(entry)

    # ----------------------------------------------------------- waiting
    def _wake(self) -> None:
        for fut in list(self._waiters):
            if not fut.done():
                fut.set_result(None)
        self._waiters.clear()

    async def wait_for(self, predicate: Callable[[], bool], timeout: float, what: str) -> None:
        """Wait until ``predicate()`` holds (checked on every message) or fail naming ``what``."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while not predicate():
            if self._link_error is not None:
                raise LinkError(self.url, f"{self._link_error} while waiting for {what}")
            remaining = deadline - loop.time()
            if remaining <= 0:
                raise WaitTimeout(self.url, f"timed out after {timeout:g} s waiting for {what}")
            await self._next_message(min(remaining, 0.25))

    async def wait_message(self, timeout: float) -> None:
        """Return at the next message from the vehicle or after ``timeout``."""
        if self._link_error is not None:
            raise LinkError(self.url, self._link_error)
        await self._next_message(timeout)

    async def _next_message(self, timeout: float) -> None:
        # asyncio.wait, not wait_for: on Python 3.11 wait_for swallows a cancel that
        # arrives together with the message, and a supervised action would not stop.
        fut: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._waiters.add(fut)
        try:
            await asyncio.wait({fut}, timeout=timeout)
        finally:
            self._waiters.discard(fut)
            fut.cancel()

    # ------------------------------------------------------------ sending
    def _send(self, fn_name: str, *args: Any) -> None:
        self._link.send(fn_name, *args)

    async def _gcs_heartbeat(self) -> None:
        while True:
            with contextlib.suppress(MavlinkError):
                self._send(
                    "heartbeat_send", MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID, 0, 0, ML.MAV_STATE_ACTIVE
                )
            await asyncio.sleep(1.0)

    async def command(self, command: int, *params: float, retries: int | None = None) -> None:
        """Send COMMAND_LONG until a COMMAND_ACK comes; raise unless it says ACCEPTED."""
        if self._link_error is not None:
            raise LinkError(self.url, self._link_error)
        name = enum_name("MAV_CMD", command)
        p = [float(x) for x in params] + [0.0] * (7 - len(params))
        loop = asyncio.get_running_loop()
        tries = self.settings.command_retries if retries is None else retries
        start = self._now()
        result: int | None = None
        attempts = 0
        for attempt in range(max(1, tries)):
            attempts = attempt + 1
            fut: asyncio.Future[int] = loop.create_future()
            self._acks[command] = fut
            try:
                self._send(
                    "command_long_send",
                    self.target_system,
                    self.target_component,
                    command,
                    attempt,
                    *p,
                )
                async with asyncio.timeout(self.settings.command_timeout):
                    result = await fut
                break
            except TimeoutError:
                if self._link_error is not None:
                    raise LinkError(self.url, self._link_error) from None
                continue
            finally:
                if self._acks.get(command) is fut:
                    del self._acks[command]
        if result is None:
            raise CommandTimeout(
                self.url,
                f"{name}: no COMMAND_ACK after {tries} tries "
                f"({self.settings.command_timeout:g} s each)",
            )
        if result != ML.MAV_RESULT_ACCEPTED:
            raise CommandRefused(
                self.url,
                name,
                enum_name("MAV_RESULT", result),
                self._texts_since(start),
                attempts=attempts,
            )

    def _texts_since(self, start: float) -> str:
        texts = [
            e.text
            for e in self.statustexts
            if e.stamp >= start and e.severity <= ML.MAV_SEVERITY_WARNING
        ]
        return "; ".join(texts[-3:])

    async def request_telemetry(self, rates_hz: Mapping[str, float]) -> None:
        """Ask for each message at its rate with MAV_CMD_SET_MESSAGE_INTERVAL."""
        for name, hz in rates_hz.items():
            msg_id = getattr(ML, f"MAVLINK_MSG_ID_{name.upper()}", None)
            if msg_id is None:
                raise MavlinkError(self.url, f"unknown telemetry message {name!r}")
            interval = -1.0 if hz <= 0 else 1e6 / hz
            try:
                await self.command(ML.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, interval)
            except CommandRefused as exc:
                if exc.result != "MAV_RESULT_UNSUPPORTED":
                    raise
                # Firmware without SET_MESSAGE_INTERVAL: fall back to the old streams.
                self._send(
                    "request_data_stream_send",
                    self.target_system,
                    self.target_component,
                    ML.MAV_DATA_STREAM_ALL,
                    max(1, round(max(rates_hz.values()))),
                    1,
                )
                return

    # ------------------------------------------------------------ operations
    @property
    def mode(self) -> str:
        mode = self.telemetry.custom_mode
        return "UNKNOWN" if mode is None else self.mode_name_of(mode)

    def mode_number(self, name: str) -> int:
        try:
            return mode_number(self.model or "copter", name)
        except KeyError as exc:
            raise MavlinkError(self.url, f"{self.model} has no mode {name!r}") from exc

    async def set_mode(self, name: str, timeout: float = 5.0) -> None:
        """MAV_CMD_DO_SET_MODE and wait until a HEARTBEAT shows the mode."""
        number = self.mode_number(name)
        old = self.telemetry.custom_mode
        self.in_control = True
        if old == number:
            self.expected_modes = frozenset({number})
            return
        previous = self.expected_modes
        self._pending_mode = (old if old is not None else -1, number)
        self.expected_modes = previous | {number}
        try:
            await self.command(ML.MAV_CMD_DO_SET_MODE, ML.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, number)
        except MavlinkError:
            self._pending_mode = None
            self.expected_modes = previous
            raise
        await self.wait_for(
            lambda: self.telemetry.custom_mode == number, timeout, f"mode {name.upper()}"
        )
        self.expected_modes = frozenset({number})

    async def wait_ekf(self, timeout: float) -> None:
        """Wait until EKF_STATUS_REPORT says the EKF has an absolute position."""
        await self.wait_for(
            self.telemetry.ekf_ready, timeout, "the EKF to use GPS (EKF_STATUS_REPORT)"
        )

    async def arm(self, timeout: float, retry_period: float = 1.0) -> None:
        """Arm, retrying while arming checks fail (FAILED), until ``timeout``.

        SYS_STATUS's pre-arm bit flickers on ArduPilot, so the only reliable test
        is to try: a refusal comes with ``PreArm: ...`` STATUSTEXTs that name why.
        A reason that belongs to a vehicle still starting up (no position estimate,
        sensors settling) is retried; any other reason given twice in a row (a
        battery below its arming voltage, a failing check) will not go away by
        waiting and fails at once with the vehicle's words.
        """
        await arm(self, timeout, retry_period)

    async def disarm(self, confirm_timeout: float = 3.0) -> None:
        """Disarm (on the ground).

        ArduPilot answers FAILED to a disarm when already disarmed, so a repeat sent
        after a lost ACK is refused although the first one worked: then a HEARTBEAT
        showing the vehicle disarmed within ``confirm_timeout`` seconds is the answer.
        """
        try:
            await self.command(ML.MAV_CMD_COMPONENT_ARM_DISARM, 0)
        except CommandRefused as exc:
            await self._done_despite_refused_repeat(
                exc, lambda: not self.telemetry.armed, confirm_timeout, "disarmed"
            )

    async def takeoff(self, altitude: float, lift_off_timeout: float = 5.0) -> None:
        """MAV_CMD_NAV_TAKEOFF to ``altitude`` metres above home (copter, GUIDED, armed).

        A repeat cannot confirm a take-off: when the first ACK is lost,
        ArduCopter answers the repeat FAILED because the copter has already left the
        ground (``do_user_takeoff`` wants ``land_complete``). Such a refusal counts as
        accepted if the copter climbs within ``lift_off_timeout`` seconds.
        """
        ground = self.telemetry.position.alt if self.telemetry.position is not None else 0.0
        try:
            await self.command(ML.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, 0, 0, altitude)
        except CommandRefused as exc:
            await self._done_despite_refused_repeat(
                exc, lambda: self._climbed_from(ground), lift_off_timeout, "the copter to climb"
            )
            log.info(
                "%s: take-off ACK lost; the repeat was refused but the copter climbs", self.url
            )

    async def _done_despite_refused_repeat(
        self, exc: CommandRefused, done: Callable[[], bool], timeout: float, what: str
    ) -> None:
        """Re-raise ``exc`` unless it answers a repeat (the first ACK was lost) with
        FAILED and ``done()`` comes true within ``timeout``: the first sending worked."""
        if exc.attempts < 2 or exc.result != "MAV_RESULT_FAILED":
            raise exc
        try:
            await self.wait_for(done, timeout, what)
        except WaitTimeout:
            raise exc from None

    def _climbed_from(self, ground: float) -> bool:
        here = self.telemetry.position
        return self.telemetry.armed and here is not None and here.alt >= ground + LIFT_OFF_M

    def send_position_target(self, target: GeoPoint) -> None:
        """SET_POSITION_TARGET_GLOBAL_INT, relative-altitude frame, position only."""
        boot_ms = int(self._now() * 1000) & 0xFFFFFFFF
        self._send(
            "set_position_target_global_int_send",
            boot_ms,
            self.target_system,
            self.target_component,
            ML.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            POSITION_ONLY_MASK,
            round(target.lat * 1e7),
            round(target.lon * 1e7),
            float(target.alt),
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        )

    async def wait_home(self, timeout: float) -> GeoPoint:
        """Home position; asks for HOME_POSITION when it has not come yet."""
        if self.telemetry.home is None:
            with contextlib.suppress(CommandRefused):
                await self.command(ML.MAV_CMD_REQUEST_MESSAGE, ML.MAVLINK_MSG_ID_HOME_POSITION)
            await self.wait_for(lambda: self.telemetry.home is not None, timeout, "HOME_POSITION")
        assert self.telemetry.home is not None
        return self.telemetry.home

    async def wait_position(self, timeout: float) -> GeoPoint:
        await self.wait_for(
            lambda: self.telemetry.position is not None, timeout, "GLOBAL_POSITION_INT"
        )
        assert self.telemetry.position is not None
        return self.telemetry.position


_HANDLERS: dict[str, Callable[[MavlinkVehicle, Any], None]] = {
    "HEARTBEAT": MavlinkVehicle._on_heartbeat,
    "GLOBAL_POSITION_INT": lambda v, m: v.telemetry.read_position(m),
    "SYS_STATUS": lambda v, m: v.telemetry.read_sys_status(m),
    "EKF_STATUS_REPORT": lambda v, m: v.telemetry.read_ekf(m),
    "HOME_POSITION": lambda v, m: v.telemetry.read_home(m),
    "COMMAND_ACK": MavlinkVehicle._on_ack,
    "STATUSTEXT": MavlinkVehicle._on_statustext,
}
