"""An asyncio client for one ArduPilot vehicle over any pymavlink connection string.

pymavlink is blocking, so a reader thread receives messages and hands each one to
the event loop (``call_soon_threadsafe``); everything else (the telemetry cache,
COMMAND_ACK matching, fault detection, waiting) runs on the loop, so a performer
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
import threading
import time
from collections import deque
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .errors import (
    CommandRefused,
    CommandTimeout,
    LinkError,
    MavlinkError,
    VehicleFault,
    WaitTimeout,
)
from .geo import GeoPoint
from .modes import MAV_AUTOPILOT_ARDUPILOTMEGA, Model, mode_name, mode_number, model_of_type

log = logging.getLogger(__name__)
ML: Any = mavlink2
T = TypeVar("T")

MAV_TYPE_GCS = 6
MAV_AUTOPILOT_INVALID = 8
MAV_COMP_ID_MISSIONPLANNER = 190
POSITION_ONLY_MASK = 0b0000_1101_1111_1000
"""SET_POSITION_TARGET_*: use x/y/z, ignore velocity, acceleration, yaw and yaw rate."""
EKF_NEEDED = 0x01 | 0x02 | 0x10 | 0x20
"""EKF_ATTITUDE | EKF_VELOCITY_HORIZ | EKF_POS_HORIZ_ABS | EKF_POS_VERT_ABS."""
EKF_BAD = 0x80 | 0x400
"""EKF_CONST_POS_MODE | EKF_UNINITIALIZED: no usable position yet."""
EXPLAIN_WAIT = 0.3
"""Seconds a mode change nobody asked for waits for the STATUSTEXT explaining it."""
LIFT_OFF_M = 0.5
"""Climb above the take-off altitude that shows a take-off is under way."""
ARMING_TEXT_PREFIXES = ("prearm:", "arm:")

DEFAULT_TELEMETRY_HZ: Mapping[str, float] = {
    "GLOBAL_POSITION_INT": 5.0,
    "SYS_STATUS": 2.0,
    "EKF_STATUS_REPORT": 2.0,
    "HOME_POSITION": 0.5,
}


@dataclass(frozen=True)
class LinkSettings:
    """Timeouts and rates of one link, in loop seconds."""

    connect_timeout: float = 30.0
    """How long to keep trying to open the link and to wait for the first HEARTBEAT."""
    heartbeat_timeout: float = 3.0
    """A supervised action fails when no HEARTBEAT came for this long."""
    command_timeout: float = 1.0
    """Wait for a COMMAND_ACK this long before re-sending the command."""
    command_retries: int = 3
    telemetry_hz: Mapping[str, float] = field(default_factory=lambda: dict(DEFAULT_TELEMETRY_HZ))
    source_system: int = 255
    source_component: int = MAV_COMP_ID_MISSIONPLANNER


@dataclass(frozen=True)
class StatusText:
    stamp: float
    severity: int
    text: str

    @property
    def severity_name(self) -> str:
        return _enum_name("MAV_SEVERITY", self.severity)


@dataclass
class Telemetry:
    """The latest values heard from the vehicle (None until first heard)."""

    position: GeoPoint | None = None
    """Latitude, longitude and altitude above home (GLOBAL_POSITION_INT.relative_alt)."""
    alt_amsl: float | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """North, east, down in m/s."""
    heading: float | None = None
    battery_remaining: float | None = None
    """Percent (SYS_STATUS.battery_remaining); None when the vehicle does not know."""
    battery_voltage: float | None = None
    ekf_flags: int | None = None
    home: GeoPoint | None = None
    """Home with its altitude above mean sea level."""
    armed: bool = False
    custom_mode: int | None = None
    system_status: int | None = None
    mav_type: int | None = None
    last_heartbeat: float = -math.inf


class MavlinkVehicle:
    """One vehicle behind one MAVLink link (``url`` in pymavlink's syntax)."""

    def __init__(self, url: str, settings: LinkSettings | None = None) -> None:
        self.url = url
        self.settings = settings or LinkSettings()
        self.telemetry = Telemetry()
        self.model: Model | None = None
        self.target_system = 0
        self.target_component = 0
        self.statustexts: deque[StatusText] = deque(maxlen=100)
        self.expected_modes: frozenset[int] = frozenset()
        """While supervised: modes the action accepts; any other mode is a fault."""
        self.expect_armed = False
        """While supervised: a disarm is a fault (a copter must not disarm mid-air)."""
        self._conn: Any = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._reader: threading.Thread | None = None
        self._closing = threading.Event()
        self._acks: dict[int, asyncio.Future[int]] = {}
        self._waiters: set[asyncio.Future[None]] = set()
        self._fault: asyncio.Future[MavlinkError] | None = None
        self._pending_mode: tuple[int, int] | None = None
        self._link_error: str | None = None
        self._tasks: list[asyncio.Task[None]] = []
        self._send_lock = threading.Lock()
        self._listeners: list[Callable[[Any], None]] = []
        self._connected = False
        self._closed_by_us = False
        self.boot_fallbacks = 0
        self.in_control = True
        """False once a failsafe or someone else took the vehicle, until we set a mode."""
        self.failsafe: str | None = None
        """The vehicle's failsafe STATUSTEXT while that failsafe holds (until disarmed)."""
        self._unexplained_mode: int | None = None
        """Mode changes ArduPilot made on its own while booting (not takeovers)."""

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
        self._conn = await self._open(deadline)
        self._closing.clear()
        self._closed_by_us = False
        self._link_error = None
        self._reader = threading.Thread(
            target=self._read_loop, name=f"mavlink-reader {self.url}", daemon=True
        )
        self._reader.start()
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

    async def _open(self, deadline: float) -> Any:
        assert self._loop is not None
        device, kwargs = _device(self.url)
        last: Exception | None = None
        while True:
            try:
                conn = await self._loop.run_in_executor(
                    None,
                    lambda: mavutil.mavlink_connection(
                        device,
                        source_system=self.settings.source_system,
                        source_component=self.settings.source_component,
                        **kwargs,
                    ),
                )
                return self._speak_mavlink2(conn)
            except (OSError, ValueError) as exc:
                last = exc
            if self._loop.time() + 0.5 > deadline:
                raise LinkError(self.url, f"cannot open the link: {last}") from last
            await asyncio.sleep(0.5)

    def _speak_mavlink2(self, conn: Any) -> Any:
        """Give the link its own MAVLink 2 codec (ArduPilot's default protocol).

        Left alone, pymavlink switches protocol on the first MAVLink 2 byte by
        setting ``MAVLINK20`` in the process environment and swapping its global
        dialect, which changes every other link in the process; this link never
        does that. MAVLink 1 frames from older vehicles still parse.
        """
        conn.mav = mavlink2.MAVLink(
            conn, srcSystem=self.settings.source_system, srcComponent=self.settings.source_component
        )
        conn.mav.robust_parsing = True
        conn.WIRE_PROTOCOL_VERSION = "2.0"
        conn.first_byte = False
        return conn

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
        self._closing.set()
        reader, self._reader = self._reader, None
        if reader is not None and self._loop is not None:
            await self._loop.run_in_executor(None, reader.join, 2.0)
        conn, self._conn = self._conn, None
        if conn is not None:
            with contextlib.suppress(Exception):
                conn.close()
        for fut in self._acks.values():
            if not fut.done():
                fut.cancel()
        self._acks.clear()
        self._wake()

    # ------------------------------------------------------------ reader side
    def _read_loop(self) -> None:
        conn = self._conn
        conn.handle_eof = self._eof  # pymavlink would only print and keep reading
        conn.handle_disconnect = self._eof
        while not self._closing.is_set():
            try:
                msg = conn.recv_msg()
            except Exception as exc:
                self._post(self._on_link_error, f"link error: {exc}")
                return
            if msg is None:
                if self._closing.is_set():
                    return
                with contextlib.suppress(Exception):
                    conn.select(0.05)
                continue
            if msg.get_type() != "BAD_DATA":
                self._post(self._on_message, msg)

    def _eof(self) -> None:
        self._closing.set()
        self._post(self._on_link_error, "link closed by the vehicle")

    def _post(self, fn: Callable[..., None], *args: Any) -> None:
        loop = self._loop
        if loop is None or loop.is_closed():
            return
        with contextlib.suppress(RuntimeError):
            loop.call_soon_threadsafe(fn, *args)

    # ------------------------------------------------------------- loop side
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
        tel = self.telemetry
        was_armed = tel.armed
        tel.last_heartbeat = self._now()
        tel.armed = bool(msg.base_mode & ML.MAV_MODE_FLAG_SAFETY_ARMED)
        tel.custom_mode = int(msg.custom_mode)
        tel.system_status = int(msg.system_status)
        tel.mav_type = int(msg.type)
        self._check_mode(tel.custom_mode)
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

    def _on_position(self, msg: Any) -> None:
        tel = self.telemetry
        tel.position = GeoPoint(msg.lat / 1e7, msg.lon / 1e7, msg.relative_alt / 1000.0)
        tel.alt_amsl = msg.alt / 1000.0
        tel.velocity = (msg.vx / 100.0, msg.vy / 100.0, msg.vz / 100.0)
        tel.heading = None if msg.hdg == 65535 else msg.hdg / 100.0

    def _on_sys_status(self, msg: Any) -> None:
        tel = self.telemetry
        tel.battery_remaining = None if msg.battery_remaining < 0 else float(msg.battery_remaining)
        tel.battery_voltage = None if msg.voltage_battery == 65535 else msg.voltage_battery / 1000

    def _on_ekf(self, msg: Any) -> None:
        self.telemetry.ekf_flags = int(msg.flags)

    def _on_home(self, msg: Any) -> None:
        self.telemetry.home = GeoPoint(msg.latitude / 1e7, msg.longitude / 1e7, msg.altitude / 1e3)

    def _on_ack(self, msg: Any) -> None:
        fut = self._acks.get(int(msg.command))
        if fut is not None and not fut.done() and msg.result != ML.MAV_RESULT_IN_PROGRESS:
            fut.set_result(int(msg.result))

    def _on_statustext(self, msg: Any) -> None:
        text = msg.text if isinstance(msg.text, str) else msg.text.decode(errors="replace")
        text = text.rstrip("\x00").strip()
        entry = StatusText(self._now(), int(msg.severity), text)
        self.statustexts.append(entry)
        log.info("%s: STATUSTEXT %s %s", self.url, entry.severity_name, text)
        lowered = text.lower()
        if lowered.startswith(ARMING_TEXT_PREFIXES):
            return  # arming checks explain refusals; arm() reports them
        if "failsafe" in lowered and "cleared" in lowered:
            self.failsafe = None
        elif "failsafe" in lowered:
            self.failsafe = text
            self._raise_fault(VehicleFault(self.url, f"failsafe: {text!r}", took_over=True))
        elif entry.severity <= ML.MAV_SEVERITY_ERROR:
            self._raise_fault(
                VehicleFault(self.url, f"vehicle reported {entry.severity_name}: {text!r}")
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

        Faults: failsafe, mode not in :attr:`expected_modes`, STATUSTEXT with
        severity ERROR or worse, disarm while :attr:`expect_armed`, no HEARTBEAT
        for ``heartbeat_timeout``, link closed.
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

    # ----------------------------------------------------------- waiting
    def _now(self) -> float:
        loop = self._loop
        return loop.time() if loop is not None else time.monotonic()

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
        conn = self._conn
        if conn is None:
            raise LinkError(self.url, "link is not open")
        with self._send_lock:
            try:
                getattr(conn.mav, fn_name)(*args)
            except OSError as exc:
                raise LinkError(self.url, f"cannot send: {exc}") from exc

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
        name = _enum_name("MAV_CMD", command)
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
                _enum_name("MAV_RESULT", result),
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
    def mode_name_of(self, number: int) -> str:
        return mode_name(self.model or "copter", number)

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

    def booting(self) -> bool:
        """Disarmed and without a position estimate yet: ArduPilot may still change
        its mode on its own (boot-time fallback), so modes set now do not stick."""
        return not self.telemetry.armed and not self.ekf_ready()

    def ekf_ready(self) -> bool:
        flags = self.telemetry.ekf_flags
        return flags is not None and flags & EKF_NEEDED == EKF_NEEDED and not flags & EKF_BAD

    async def wait_ekf(self, timeout: float) -> None:
        """Wait until EKF_STATUS_REPORT says the EKF has an absolute position."""
        await self.wait_for(self.ekf_ready, timeout, "the EKF to use GPS (EKF_STATUS_REPORT)")

    async def arm(self, timeout: float, retry_period: float = 1.0) -> None:
        """Arm, retrying while arming checks fail (FAILED), until ``timeout``.

        SYS_STATUS's pre-arm bit flickers on ArduPilot, so the only reliable test
        is to try: a refusal comes with ``PreArm: ...`` STATUSTEXTs that name why.
        A reason that belongs to a vehicle still starting up (no position estimate,
        sensors settling) is retried; any other reason given twice in a row (a
        battery below its arming voltage, a failing check) will not go away by
        waiting and fails at once with the vehicle's words.
        """
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        start = self._now()
        previous: str | None = None
        while not self.telemetry.armed:
            tried = self._now()
            try:
                await self.command(ML.MAV_CMD_COMPONENT_ARM_DISARM, 1)
            except CommandRefused as exc:
                if exc.result not in ("MAV_RESULT_FAILED", "MAV_RESULT_TEMPORARILY_REJECTED"):
                    raise
                reason = self._arming_texts(tried) or exc.reason
                if reason and reason == previous and not _starting_up(reason):
                    raise CommandRefused(self.url, "arming", exc.result, reason) from exc
                previous = reason
                if loop.time() + retry_period > deadline:
                    why = self._arming_texts(start) or exc.reason
                    raise CommandRefused(
                        self.url, "arming", exc.result, f"still refused after {timeout:g} s: {why}"
                    ) from exc
                await asyncio.sleep(retry_period)
                continue
            await self.wait_for(
                lambda: self.telemetry.armed,
                max(1.0, deadline - loop.time()),
                "a HEARTBEAT showing the vehicle armed",
            )

    def _arming_texts(self, start: float) -> str:
        seen: list[str] = []
        for entry in self.statustexts:
            arming = entry.text.lower().startswith(ARMING_TEXT_PREFIXES)
            if arming and entry.stamp >= start and entry.text not in seen:
                seen.append(entry.text)
        return "; ".join(seen[-3:])

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
    "GLOBAL_POSITION_INT": MavlinkVehicle._on_position,
    "SYS_STATUS": MavlinkVehicle._on_sys_status,
    "EKF_STATUS_REPORT": MavlinkVehicle._on_ekf,
    "HOME_POSITION": MavlinkVehicle._on_home,
    "COMMAND_ACK": MavlinkVehicle._on_ack,
    "STATUSTEXT": MavlinkVehicle._on_statustext,
}


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


def _starting_up(reason: str) -> bool:
    lowered = reason.lower()
    return any(word in lowered for word in STARTING_UP_WORDS)


def _enum_name(enum: str, value: int) -> str:
    entry = ML.enums.get(enum, {}).get(value)
    return entry.name if entry is not None else f"{enum}({value})"


def _device(url: str) -> tuple[str, dict[str, Any]]:
    """pymavlink device string and options for ``url``.

    ``tcp:``/``udp:``/``udpin:``/``udpout:`` go to pymavlink unchanged;
    ``serial:/dev/ttyUSB0:57600`` (or a bare device path, optionally ``:baud``)
    opens a serial port.
    """
    if url.startswith(("tcp:", "udp:", "udpin:", "udpout:", "udpbcast:", "tcpin:")):
        parts = url.split(":")
        if len(parts) != 3 or not parts[2].isdigit():
            raise LinkError(url, "a network URL must look like tcp:HOST:PORT")
        options: dict[str, Any] = {"retries": 0} if url.startswith("tcp:") else {}
        return url, options
    path = url.removeprefix("serial:")
    baud = 115200
    head, _, tail = path.rpartition(":")
    if head and tail.isdigit():
        path, baud = head, int(tail)
    if not path:
        raise LinkError(url, "no serial device given")
    return path, {"baud": baud}
