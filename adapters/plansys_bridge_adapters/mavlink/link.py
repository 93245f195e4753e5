"""The MAVLink link of one vehicle: the pymavlink connection and the thread reading it.

The event loop watches the connection's file descriptor and parses each message
as its bytes arrive (no thread, no polling); only a connection without a
descriptor gets a reader thread that hands messages to the loop. The client on the
loop sends under a lock (a thread may send too). The link speaks
MAVLink 2 on its own codec (see :meth:`MavlinkLink._speak_mavlink2`).
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from plansys_bridge.retry import retrying

from .errors import LinkError

MAV_COMP_ID_MISSIONPLANNER = 190
DRAIN_BATCH = 64
"""Messages parsed in one go before the loop runs other work (a busy link never
starves the client's own timers)."""

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


class MavlinkLink:
    """One open pymavlink connection (``url`` in pymavlink's syntax) and its reader."""

    def __init__(self, url: str, settings: LinkSettings) -> None:
        self.url = url
        self.settings = settings
        self._conn: Any = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._reader: threading.Thread | None = None
        self._closing = threading.Event()
        self._send_lock = threading.Lock()
        self._fd: int | None = None

    @property
    def is_open(self) -> bool:
        return self._conn is not None

    async def open(self, deadline: float) -> None:
        """Open the connection, retrying every 0.5 s until loop time ``deadline``."""
        loop = self._loop = asyncio.get_running_loop()
        device, kwargs = _device(self.url)

        def connect() -> Any:
            return mavutil.mavlink_connection(
                device,
                source_system=self.settings.source_system,
                source_component=self.settings.source_component,
                **kwargs,
            )

        try:
            async for attempt in retrying(
                every=0.5, within=deadline - loop.time(), on=(OSError, ValueError)
            ):
                with attempt:
                    conn = await loop.run_in_executor(None, connect)
        except (OSError, ValueError) as exc:
            raise LinkError(self.url, f"cannot open the link: {exc}") from exc
        self._conn = self._speak_mavlink2(conn)
        self._closing.clear()

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

    def start_reading(
        self, on_message: Callable[[Any], None], on_error: Callable[[str], None]
    ) -> None:
        """Deliver each message to ``on_message(msg)`` and a broken link to
        ``on_error(reason)``, both on the loop that opened the link.

        Where the connection has a file descriptor (TCP, UDP, serial on POSIX) the
        loop itself watches it (``add_reader``): a message is parsed the moment its
        bytes arrive, with no thread between the socket and the client. Elsewhere
        a reader thread waits on pymavlink and hands messages over.
        """
        conn = self._conn

        def eof() -> None:
            self._closing.set()
            self._post(on_error, "link closed by the vehicle")

        conn.handle_eof = eof  # pymavlink would only print and keep reading
        conn.handle_disconnect = eof
        fd = self._descriptor()
        if fd is not None and self._loop is not None:
            self._fd = fd
            self._loop.add_reader(fd, self._drain, on_message, on_error)
            return
        self._reader = threading.Thread(
            target=self._read_loop,
            args=(on_message, on_error),
            name=f"mavlink-reader {self.url}",
            daemon=True,
        )
        self._reader.start()

    def _descriptor(self) -> int | None:
        """The file descriptor the loop can watch (None: Windows serial ports)."""
        fd = getattr(self._conn, "fd", None)
        return fd if isinstance(fd, int) else None

    def _drain(self, on_message: Callable[[Any], None], on_error: Callable[[str], None]) -> None:
        """On the loop: parse what has arrived, at most a batch before yielding."""
        conn = self._conn
        for _ in range(DRAIN_BATCH):
            if conn is None or self._closing.is_set():
                self._stop_watching()
                return
            try:
                msg = conn.recv_msg()
            except Exception as exc:
                self._stop_watching()
                self._post(on_error, f"link error: {exc}")  # after a posted EOF
                return
            if msg is None:
                return
            if msg.get_type() != "BAD_DATA":
                on_message(msg)
        # more may sit in pymavlink's buffer (several messages in one datagram)
        if self._loop is not None:
            self._loop.call_soon(self._drain, on_message, on_error)

    def _stop_watching(self) -> None:
        fd, self._fd = self._fd, None
        if fd is not None and self._loop is not None and not self._loop.is_closed():
            self._loop.remove_reader(fd)

    def _read_loop(
        self, on_message: Callable[[Any], None], on_error: Callable[[str], None]
    ) -> None:
        conn = self._conn
        while not self._closing.is_set():
            try:
                msg = conn.recv_msg()
            except Exception as exc:
                self._post(on_error, f"link error: {exc}")
                return
            if msg is None:
                if self._closing.is_set():
                    return
                with contextlib.suppress(Exception):
                    conn.select(0.05)
                continue
            if msg.get_type() != "BAD_DATA":
                self._post(on_message, msg)

    def _post(self, fn: Callable[..., None], *args: Any) -> None:
        loop = self._loop
        if loop is None or loop.is_closed():
            return
        with contextlib.suppress(RuntimeError):
            loop.call_soon_threadsafe(fn, *args)

    def send(self, fn_name: str, *args: Any) -> None:
        """Call pymavlink's ``conn.mav.<fn_name>(*args)`` (e.g. ``heartbeat_send``)."""
        conn = self._conn
        if conn is None:
            raise LinkError(self.url, "link is not open")
        with self._send_lock:
            try:
                getattr(conn.mav, fn_name)(*args)
            except OSError as exc:
                raise LinkError(self.url, f"cannot send: {exc}") from exc

    async def close(self) -> None:
        """Stop the reader thread and close the connection (idempotent)."""
        self._closing.set()
        self._stop_watching()
        reader, self._reader = self._reader, None
        if reader is not None and self._loop is not None:
            await self._loop.run_in_executor(None, reader.join, 2.0)
        conn, self._conn = self._conn, None
        if conn is not None:
            with contextlib.suppress(Exception):
                conn.close()


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
