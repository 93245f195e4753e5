"""A python-can bus for asyncio code: open from config, read, classify, send.

The interface and channel are configuration (``virtual`` in tests, ``socketcan`` /
``can0`` on a robot); nothing else in the adapter knows which. Received frames are
sorted here into three streams for a :class:`FrameListener`: decoded DBC frames,
CAN error frames, and bus errors (the driver failing). Everything else that arrives
(unknown IDs, wrong DLC, remote frames, out-of-range signals) is counted in
:class:`BusCounters` and logged with a back-off, and never reaches the listener:
a noisy bus must not crash or confuse the adapter.

Two readers:

- ``notifier``: on an interface with a file descriptor (SocketCAN) the event loop
  watches the socket and drains it when readable; on the others python-can's
  :class:`can.Notifier` thread feeds an :class:`can.AsyncBufferedReader`. This is
  the choice on a robot.
- ``poll``: a task on the event loop drains ``bus.recv(0)`` every ``poll_period``.
  No threads, so it runs in virtual time (the project's VirtualClock) and tests are
  deterministic; the cost is up to ``poll_period`` of added latency.
- ``manual``: no reader; the owner calls :meth:`CanBusClient.drain` from its own
  loop (the base double does, once per physics step, like a controller's main loop).
"""

from __future__ import annotations

import asyncio
import contextlib
import difflib
import logging
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

import can

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.errors import AdapterError
from plansys_bridge.retry import retrying

from .dbc import Frame, MalformedFrame, MobileBaseDbc

_LOG = logging.getLogger(__name__)

ReaderKind = Literal["auto", "notifier", "poll", "manual"]


class BusOpenError(AdapterError):
    """The CAN interface could not be opened (missing driver, link down, bad channel)."""


class BusSendError(AdapterError):
    """A frame could not be sent (bus-off, TX buffer full, interface gone)."""


@dataclass(frozen=True)
class BusConfig:
    """Where and how to reach the CAN bus."""

    interface: str = "virtual"
    channel: str = "plansys_can0"
    bitrate: int | None = None
    reader: ReaderKind = "auto"
    poll_period: float = 0.005
    send_timeout: float = 0.05
    reopen_period: float | None = 1.0
    """After a driver error, try to reopen the interface this often (None: never)."""
    options: Mapping[str, Any] = field(default_factory=dict)
    """Extra keyword arguments for :class:`can.Bus` (e.g. ``fd``, ``receive_own_messages``)."""
    origin: str = "the mission file"
    """Where interface and channel came from (the mission file, python-can's config)."""

    def describe(self) -> str:
        return f"{self.interface}:{self.channel}"


PYTHON_CAN_CONFIG = "python-can's configuration (CAN_INTERFACE/CAN_CHANNEL, can.rc, ~/.canrc)"


def choose_interface(
    interface: str | None, channel: str | None, *, simulated: bool
) -> tuple[str, str, str]:
    """Interface, channel and their origin for a bus entry, checked before anything opens.

    A named interface must be one python-can knows (a typo such as ``socketcann`` is an
    error now, not 30 s of silence later). Without one, python-can's own configuration
    chain decides, as it does for ``can.Bus()``; with nothing configured there, only a
    simulated base falls back to the virtual bus, saying so.
    """
    if interface is not None:
        check_known_interface(interface, "interface")
        return interface, channel or "plansys_can0", "the mission file"
    found: dict[str, Any] = {}
    # python-can's own order (can.util.load_config): can.rc, environment, config files
    for source in (can.rc, can.util.load_environment_config(), can.util.load_file_config()):
        for name, value in source.items():
            found.setdefault("interface" if name == "bustype" else name, value)
    if found.get("interface"):
        name = str(found["interface"])
        check_known_interface(name, f"interface from {PYTHON_CAN_CONFIG}")
        return name, str(found.get("channel") or channel or "can0"), PYTHON_CAN_CONFIG
    if simulated:
        return "virtual", channel or "plansys_can0", "the default for a simulated base"
    raise ValueError(
        f"no CAN interface: give bus.interface (e.g. socketcan) or set one in {PYTHON_CAN_CONFIG}"
    )


def check_known_interface(interface: str, what: str) -> None:
    known = sorted(can.interfaces.VALID_INTERFACES)
    if interface not in known:
        close = difflib.get_close_matches(interface, known, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else f" (known: {', '.join(known)})"
        raise ValueError(f"unknown python-can {what} {interface!r}{hint}")


@dataclass
class BusCounters:
    """What went over the bus; malformed frames by kind (``unknown_id``, ``bad_dlc``, ...)."""

    received: int = 0
    decoded: int = 0
    sent: int = 0
    error_frames: int = 0
    send_errors: int = 0
    bus_errors: int = 0
    reopens: int = 0
    malformed: Counter[str] = field(default_factory=Counter)

    @property
    def malformed_total(self) -> int:
        return sum(self.malformed.values())


class FrameListener(Protocol):
    """Receives what the bus client sorted out, always on the event loop."""

    def on_frame(self, frame: Frame) -> None: ...

    def on_error_frame(self, msg: can.Message) -> None: ...

    def on_bus_error(self, exc: Exception) -> None: ...


class _BusErrorMarker:
    """Put into the reader's queue when python-can's reader thread fails."""

    def __init__(self, exc: Exception) -> None:
        self.exc = exc


def _fileno(bus: can.BusABC) -> int | None:
    """The bus's file descriptor if it has one the event loop can watch."""
    try:
        fd = bus.fileno()
    except (NotImplementedError, OSError, AttributeError):
        return None
    return fd if isinstance(fd, int) and fd >= 0 else None


class _LoopReader(can.AsyncBufferedReader):
    """AsyncBufferedReader that also forwards reader-thread errors into the queue."""

    def on_error(self, exc: Exception) -> None:
        self.buffer.put_nowait(_BusErrorMarker(exc))  # type: ignore[arg-type]


def describe_frame(msg: can.Message) -> str:
    """Short text of a raw frame for logs: ``0x123 [3] 01 02 03`` (extended IDs: 8 digits)."""
    width = 8 if msg.is_extended_id else 3
    frame_id = f"0x{msg.arbitration_id:0{width}X}"
    kind = " remote" if msg.is_remote_frame else ""
    return f"{frame_id}{kind} [{len(msg.data)}] {bytes(msg.data).hex(' ')}".rstrip()


BusFactory = Callable[..., can.BusABC]


class CanBusClient:
    """One python-can bus, its reader, and the DBC classification of its frames.

    ``bus_factory`` builds the python-can bus from the config's keywords
    (``interface``, ``channel``, ``bitrate``, options); :class:`can.Bus` by default.
    """

    def __init__(
        self,
        config: BusConfig,
        dbc: MobileBaseDbc,
        listener: FrameListener,
        bus_factory: BusFactory = can.Bus,
    ) -> None:
        self.config = config
        self.dbc = dbc
        self.listener = listener
        self.counters = BusCounters()
        self.frame_hooks: list[Callable[[can.Message], None]] = []
        """Also called with every received data frame, before DBC decoding (sensing
        rules read any signal of the database from them)."""
        self._factory = bus_factory
        self._kind: ReaderKind = "manual"
        self._bus: can.BusABC | None = None
        self._fd: int | None = None
        self._notifier: can.Notifier | None = None
        self._task: asyncio.Task[None] | None = None
        self._reopen_task: asyncio.Task[None] | None = None
        self._broken: can.BusABC | None = None
        self._closing = False

    @property
    def is_open(self) -> bool:
        return self._bus is not None

    @property
    def reopening(self) -> bool:
        """A driver error closed the interface and it is being reopened."""
        return self._reopen_task is not None

    @property
    def bus(self) -> can.BusABC | None:
        """The python-can bus while open (for diagnostics such as ``bus.state``)."""
        return self._bus

    async def open(self, reader: ReaderKind | None = None) -> None:
        """Open the interface and start reading (``reader`` overrides the config)."""
        if self._bus is not None:
            return
        kind = reader or self.config.reader
        self._kind = "notifier" if kind == "auto" else kind
        self._closing = False
        self._bus = self._create_bus()
        if self.config.interface == "socketcan" and self.config.bitrate is not None:
            # python-can's SocketcanBus swallows ``bitrate`` without a word: the kernel
            # interface keeps the rate it was brought up with.
            _LOG.warning(
                "%s: bitrate %d is not applied by socketcan; the interface runs at the rate "
                "set with `ip link set %s type can bitrate N` (check `ip -details link show %s`)",
                self.config.describe(),
                self.config.bitrate,
                self.config.channel,
                self.config.channel,
            )
        self._start_reader(self._bus)

    def _create_bus(self) -> can.BusABC:
        kwargs: dict[str, Any] = dict(self.config.options)
        if self.config.bitrate is not None:
            kwargs["bitrate"] = self.config.bitrate
        try:
            return self._factory(
                interface=self.config.interface, channel=self.config.channel, **kwargs
            )
        except (can.CanError, OSError, ValueError, ImportError, TypeError) as exc:
            raise BusOpenError(f"cannot open CAN bus {self.config.describe()}: {exc}") from exc

    def _start_reader(self, bus: can.BusABC) -> None:
        loop = asyncio.get_running_loop()
        if self._kind == "notifier":
            fd = _fileno(bus)
            if fd is not None:
                # SocketCAN: the loop watches the socket. Our own guarded drain instead of
                # the Notifier's, so a failing socket becomes one bus error, not a spin.
                loop.add_reader(fd, self.drain)
                self._fd = fd
            else:
                reader = _LoopReader()
                self._notifier = can.Notifier(bus, [reader], timeout=0.1, loop=loop)
                self._task = loop.create_task(self._pump_notifier(reader))
        elif self._kind == "poll" and self._task is None:
            self._task = loop.create_task(self._poll())

    async def _stop_reader(self) -> None:
        """Stop watching the current bus (the poll task survives: it follows ``_bus``)."""
        if self._fd is not None:
            asyncio.get_running_loop().remove_reader(self._fd)
            self._fd = None
        if self._notifier is not None:
            notifier, self._notifier = self._notifier, None
            task, self._task = self._task, None
            if task is not None and task is not asyncio.current_task():
                await cancel_and_wait(task)
            # Joining python-can's reader thread blocks for up to its timeout.
            await asyncio.get_running_loop().run_in_executor(None, notifier.stop, 1.0)

    async def close(self) -> None:
        """Stop reading and shut the interface down; safe to call twice."""
        self._closing = True
        if self._reopen_task is not None:
            await cancel_and_wait(self._reopen_task)
            self._reopen_task = None
        await self._stop_reader()
        if self._task is not None:
            await cancel_and_wait(self._task)
            self._task = None
        for bus in (self._broken, self._bus):
            if bus is not None:
                with contextlib.suppress(Exception):
                    bus.shutdown()
        self._broken = self._bus = None

    def send_frame(self, frame: Frame) -> None:
        """Encode with the DBC and send; a failure raises :class:`BusSendError`."""
        self.send_raw(self.dbc.encode(frame))

    def send_raw(self, msg: can.Message) -> None:
        if self._bus is None:
            raise BusSendError(f"CAN bus error on {self.config.describe()}: not open")
        try:
            self._bus.send(msg, timeout=self.config.send_timeout)
        except can.CanError as exc:
            self.counters.send_errors += 1
            raise BusSendError(
                f"CAN bus error on {self.config.describe()}: cannot send "
                f"{describe_frame(msg)}: {exc}"
            ) from exc
        self.counters.sent += 1

    def dispatch(self, msg: can.Message) -> None:
        """Classify one received frame and hand it to the listener (or count it)."""
        self.counters.received += 1
        if msg.is_error_frame:
            self.counters.error_frames += 1
            self.listener.on_error_frame(msg)
            return
        for hook in list(self.frame_hooks):
            hook(msg)
        try:
            frame = self.dbc.decode(msg)
        except MalformedFrame as exc:
            self._count_malformed(exc, msg)
            return
        self.counters.decoded += 1
        self.listener.on_frame(frame)

    def _count_malformed(self, exc: MalformedFrame, msg: can.Message) -> None:
        self.counters.malformed[exc.kind] += 1
        count = self.counters.malformed[exc.kind]
        # Log the 1st, 2nd, 4th, 8th, ... of each kind: visible, but a flood stays quiet.
        level = logging.WARNING if count & (count - 1) == 0 else logging.DEBUG
        _LOG.log(
            level,
            "%s: ignored malformed frame %s (%s; %d %s so far)",
            self.config.describe(),
            describe_frame(msg),
            exc,
            count,
            exc.kind,
        )

    def _bus_failed(self, exc: Exception) -> None:
        self.counters.bus_errors += 1
        _LOG.error("%s: bus error: %s", self.config.describe(), exc)
        if self._fd is not None:
            asyncio.get_running_loop().remove_reader(self._fd)
            self._fd = None
        if self.config.reopen_period is not None and not self._closing and self._bus is not None:
            # Stop using the failed interface at once (sends fail clearly as "not open")
            # and bring it back in the background: a link that flaps heals by itself.
            self._broken, self._bus = self._bus, None
            if self._reopen_task is None:
                self._reopen_task = asyncio.get_running_loop().create_task(self._reopen())
        self.listener.on_bus_error(exc)

    async def _reopen(self) -> None:
        period = self.config.reopen_period
        assert period is not None

        def retrying_in(exc: BaseException, wait: float) -> None:
            _LOG.warning("%s; retrying in %g s", exc, wait)

        try:
            await asyncio.sleep(period)
            async for attempt in retrying(every=period, on=BusOpenError, before_retry=retrying_in):
                with attempt:
                    if self._closing:
                        return
                    await self._stop_reader()
                    if self._broken is not None:
                        broken, self._broken = self._broken, None
                        with contextlib.suppress(Exception):
                            broken.shutdown()
                    bus = self._create_bus()
            self._bus = bus
            self._start_reader(bus)
            self.counters.reopens += 1
            _LOG.warning("%s: reopened after a bus error", self.config.describe())
        finally:
            self._reopen_task = None

    def _dispatch_safely(self, msg: can.Message) -> None:
        try:
            self.dispatch(msg)
        except Exception:
            # A listener bug must not stop the reader: every later frame would be lost.
            _LOG.exception("%s: error handling %s", self.config.describe(), describe_frame(msg))

    async def _pump_notifier(self, reader: _LoopReader) -> None:
        while True:
            item: object = await reader.get_message()
            if isinstance(item, _BusErrorMarker):
                self._bus_failed(item.exc)
                continue
            assert isinstance(item, can.Message)
            self._dispatch_safely(item)

    def drain(self, max_frames: int = 256) -> int:
        """Handle what is queued now, up to ``max_frames``; returns how many frames.

        A driver error goes to the listener's ``on_bus_error`` and ends the drain.
        """
        bus = self._bus
        if bus is None:
            return 0
        handled = 0
        try:
            while handled < max_frames:
                msg = bus.recv(0)
                if msg is None:
                    break
                handled += 1
                self._dispatch_safely(msg)
        except can.CanError as exc:
            self._bus_failed(exc)
        return handled

    async def _poll(self) -> None:
        period = self.config.poll_period
        while not self._closing:
            errors = self.counters.bus_errors
            self.drain()
            # After a driver error, back off instead of spinning on a dead interface.
            await asyncio.sleep(max(period, 0.1) if self.counters.bus_errors > errors else period)
