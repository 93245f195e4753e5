"""The vehicle double on a real socket: one thread, one TCP server or UDP port.

SITL listens on TCP and serves one ground station; :class:`VehicleDouble` does the
same on 127.0.0.1 (port 0 = any free port), or listens on a UDP port and answers the
last sender. The thread advances the simulation on the wall clock times ``speedup``,
so a test at speedup 20 sees a 20 s EKF delay pass in one second.
"""

from __future__ import annotations

import contextlib
import selectors
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import replace
from types import TracebackType
from typing import Any, Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..errors import LinkError
from ..modes import Model
from .sim import SimParams, VehicleSim

Transport = Literal["tcp", "udp"]

MAX_SUBSTEP = 0.05
"""Longest simulated step (s); larger wall-clock gaps are cut into steps of this size."""
MAX_GAP = 2.0
"""Longest simulated time one loop pass may add (a stalled process does not teleport)."""


class VehicleDouble:
    """A simulated ArduPilot vehicle serving MAVLink on a loopback socket.

    ``transport="tcp"``: a server, the client connects (``tcp:HOST:PORT``).
    ``transport="udp"``: listens, the client sends first (``udpout:HOST:PORT``);
    with ``peer=(host, port)`` it sends there instead and the client listens
    (``udpin:HOST:PORT``). :attr:`url` is the client's connection string.
    Use as a context manager, or :meth:`start` / :meth:`stop`. The fault methods
    are safe to call from any thread while it runs.
    """

    def __init__(
        self,
        model: Model = "copter",
        *,
        speedup: float = 1.0,
        port: int = 0,
        host: str = "127.0.0.1",
        transport: Transport = "tcp",
        params: SimParams | None = None,
        tick: float = 0.005,
        peer: tuple[str, int] | None = None,
        **overrides: Any,
    ) -> None:
        if model not in ("copter", "rover"):
            raise ValueError(f"vehicle double model must be 'copter' or 'rover', not {model!r}")
        if speedup <= 0:
            raise ValueError(f"vehicle double speedup must be positive, not {speedup!r}")
        if transport not in ("tcp", "udp"):
            raise ValueError(f"vehicle double transport must be 'tcp' or 'udp', not {transport!r}")
        base = params if params is not None else SimParams()
        self.params = replace(base, model=model, **overrides)
        self.speedup = float(speedup)
        self.host = host
        self.transport: Transport = transport
        self._requested_port = port
        self._tick = tick
        self.sim = VehicleSim(self.params)
        self._lock = threading.RLock()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._sock: socket.socket | None = None
        self._client: socket.socket | None = None
        self._peer: tuple[str, int] | None = peer
        """UDP: where to send; the last sender once one has been heard."""
        self.out = peer
        """UDP ``--out`` address given at construction (the client listens there)."""
        if peer is not None and transport != "udp":
            raise ValueError("vehicle double peer (an --out address) needs transport 'udp'")
        self._parser = mavlink2.MAVLink(None)
        self._parser.robust_parsing = True
        self.port = 0
        self.received: deque[str] = deque(maxlen=1000)
        """Types of the latest messages heard from the client (for tests)."""

    # ------------------------------------------------------------- lifecycle
    @property
    def url(self) -> str:
        """The pymavlink connection string a client uses to reach this double."""
        if self.out is not None:
            return f"udpin:{self.out[0]}:{self.out[1]}"
        scheme = "tcp" if self.transport == "tcp" else "udpout"
        return f"{scheme}:{self.host}:{self.port}"

    def start(self) -> VehicleDouble:
        """Bind the socket and start the simulation thread; returns self."""
        if self._thread is not None:
            return self
        kind = socket.SOCK_STREAM if self.transport == "tcp" else socket.SOCK_DGRAM
        sock = socket.socket(socket.AF_INET, kind)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((self.host, self._requested_port))
        except OSError as exc:
            sock.close()
            raise LinkError(
                f"{self.transport}:{self.host}:{self._requested_port}",
                f"vehicle double cannot bind: {exc}",
            ) from exc
        if self.transport == "tcp":
            sock.listen(1)
        sock.setblocking(False)
        self._sock = sock
        self.port = sock.getsockname()[1]
        self._stop.clear()
        if self.out is not None:
            # Sending to a listening client, like SITL's --out: nobody will speak
            # first, so the clock starts now.
            self.sim.connect()
        self._thread = threading.Thread(
            target=self._run, name=f"mavlink-double-{self.params.model}-{self.port}", daemon=True
        )
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread and close every socket."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        for sock in (self._client, self._sock):
            if sock is not None:
                with contextlib.suppress(OSError):
                    sock.close()
        self._client = None
        self._sock = None

    def __enter__(self) -> VehicleDouble:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    # ---------------------------------------------------------------- faults
    def failsafe(self, reason: str = "Battery") -> None:
        """A failsafe fires (STATUSTEXT ``<reason> Failsafe``, copter RTL/LAND, rover HOLD)."""
        self._locked(lambda: self.sim.inject_failsafe(reason))

    def change_mode(self, mode: str) -> None:
        """Someone else switches the flight mode."""
        self._locked(lambda: self.sim.inject_mode_change(mode))

    def wind(self, speed: float, from_deg: float = 0.0) -> None:
        """Wind of ``speed`` m/s from ``from_deg`` degrees; stronger than ``wind_limit``,
        it blows an airborne copter off its course (ArduPilot says nothing)."""
        self._locked(lambda: self.sim.inject_wind(speed, from_deg))

    def drop_link(self, seconds: float) -> None:
        """The radio link goes silent both ways for ``seconds`` of simulated time."""
        self._locked(lambda: self.sim.inject_link_drop(seconds))

    def refuse_next(self, command: int, result: int = mavlink2.MAV_RESULT_DENIED) -> None:
        """The next MAV_CMD ``command`` is answered with ``result`` and not obeyed."""
        self._locked(lambda: self.sim.refuse_next(command, result))

    def lose_next_ack(self, command: int) -> None:
        """The next MAV_CMD ``command`` is obeyed but its COMMAND_ACK never arrives."""
        self._locked(lambda: self.sim.lose_next_ack(command))

    def statustext(self, text: str, severity: int = mavlink2.MAV_SEVERITY_ERROR) -> None:
        """The vehicle sends a STATUSTEXT (e.g. an error a test wants the client to catch)."""
        self._locked(lambda: self.sim.statustext(severity, text))

    def set_battery(self, percent: float) -> None:
        """Set the remaining battery (%), e.g. to trigger low-battery reactions."""

        def apply() -> None:
            self.sim.battery = float(percent)

        self._locked(apply)

    def state(self) -> Mapping[str, Any]:
        """A snapshot of the vehicle: time, armed, mode, alt, north, east, battery, ..."""
        with self._lock:
            return dict(self.sim.snapshot())

    def wait_for(self, predicate: Callable[[Mapping[str, Any]], bool], timeout: float) -> bool:
        """Poll :meth:`state` until ``predicate`` holds or ``timeout`` wall seconds pass."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate(self.state()):
                return True
            time.sleep(0.01)
        return predicate(self.state())

    def _locked(self, action: Callable[[], None]) -> None:
        with self._lock:
            action()

    # ------------------------------------------------------------------ loop
    def _run(self) -> None:
        selector = selectors.DefaultSelector()
        assert self._sock is not None
        selector.register(self._sock, selectors.EVENT_READ)
        last = time.monotonic()
        try:
            while not self._stop.is_set():
                for key, _ in selector.select(self._tick):
                    self._readable(selector, key.fileobj)  # type: ignore[arg-type]
                now = time.monotonic()
                gap = min((now - last) * self.speedup, MAX_GAP)
                last = now
                with self._lock:
                    while gap > 1e-9:
                        step = min(gap, MAX_SUBSTEP)
                        self.sim.step(step)
                        gap -= step
                    frames = self.sim.take_output()
                self._write(frames)
        finally:
            selector.close()

    def _readable(self, selector: selectors.BaseSelector, sock: socket.socket) -> None:
        if self.transport == "tcp" and sock is self._sock:
            with contextlib.suppress(BlockingIOError):
                conn, _ = sock.accept()
                conn.setblocking(False)
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                if self._client is not None:  # one ground station at a time, like SITL
                    selector.unregister(self._client)
                    self._client.close()
                self._client = conn
                self._parser = mavlink2.MAVLink(None)
                self._parser.robust_parsing = True
                selector.register(conn, selectors.EVENT_READ)
                with self._lock:
                    self.sim.connect()
            return
        try:
            if self.transport == "udp":
                data, peer = sock.recvfrom(65535)
                self._peer = (peer[0], peer[1])
            else:
                data = sock.recv(65535)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:
            if self.transport == "tcp":
                selector.unregister(sock)
                sock.close()
                self._client = None
            return
        messages = self._parser.parse_buffer(data) or []
        with self._lock:
            self.sim.connect()
            for msg in messages:
                if msg.get_type() == "BAD_DATA":
                    continue
                self.received.append(msg.get_type())
                self.sim.handle(msg)

    def _write(self, frames: list[bytes]) -> None:
        if not frames:
            return
        data = b"".join(frames)
        try:
            if self.transport == "tcp" and self._client is not None:
                self._client.sendall(data)
            elif self.transport == "udp" and self._peer is not None and self._sock is not None:
                for frame in frames:
                    self._sock.sendto(frame, self._peer)
        except (BlockingIOError, OSError):
            pass  # a slow or gone client loses telemetry, as over a radio
