"""The bus client: both readers, classification of what arrives, driver errors."""

from __future__ import annotations

import asyncio
import logging
import socket
import threading
from collections import deque
from typing import Any

import can
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from plansys_bridge_adapters.can.bus import (
    BusConfig,
    BusOpenError,
    BusSendError,
    CanBusClient,
    describe_frame,
)
from plansys_bridge_adapters.can.dbc import Frame, MobileBaseDbc, OdomPose, OdomTwist
from plansys_bridge_adapters.can.monitor import BaseMonitor, describe_error_frame

from plansys_bridge.clock import VirtualClock, WallClock, run

DBC = MobileBaseDbc.load()


class Sink:
    def __init__(self) -> None:
        self.frames: list[Frame] = []
        self.error_frames: list[can.Message] = []
        self.bus_errors: list[Exception] = []
        self.arrived = asyncio.Event()

    def on_frame(self, frame: Frame) -> None:
        self.frames.append(frame)
        self.arrived.set()

    def on_error_frame(self, msg: can.Message) -> None:
        self.error_frames.append(msg)

    def on_bus_error(self, exc: Exception) -> None:
        self.bus_errors.append(exc)


class SocketPairBus(can.BusABC):
    """A python-can interface whose receive queue wakes a socket, as SocketCAN's does.

    The kernel's SocketCAN is not available here; this exercises the same path of
    the client: the event loop watching the bus's file descriptor.
    """

    def __init__(self, channel: str = "pair", **kwargs: Any) -> None:
        super().__init__(channel=channel, **kwargs)
        self.channel_info = f"socketpair {channel}"
        self._rx, self._tx = socket.socketpair()
        self._rx.setblocking(False)
        self.queue: deque[can.Message] = deque()
        self.failure: Exception | None = None
        self.recv_calls = 0

    def fileno(self) -> int:
        return self._rx.fileno()

    def inject(self, msg: can.Message) -> None:
        self.queue.append(msg)
        self._tx.send(b"f")

    def fail(self, exc: Exception) -> None:
        """Make the socket readable for good and every receive fail (a downed link)."""
        self.failure = exc
        self._tx.send(b"!")

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        self.recv_calls += 1
        if self.failure is not None:
            raise self.failure
        try:
            self._rx.recv(1)
        except BlockingIOError:
            return None, False
        return self.queue.popleft(), False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        return None

    def shutdown(self) -> None:
        super().shutdown()
        self._rx.close()
        self._tx.close()


class Raising(Sink):
    def on_frame(self, frame: Frame) -> None:
        super().on_frame(frame)
        if len(self.frames) == 1:
            raise RuntimeError("listener bug")


def test_notifier_reader_on_the_wall_clock(channel: str) -> None:
    """python-can's Notifier + AsyncBufferedReader, its thread stopped on close."""

    async def main() -> None:
        sink = Sink()
        client = CanBusClient(BusConfig(channel=channel, reader="notifier"), DBC, sink)
        other = can.Bus(interface="virtual", channel=channel)
        await client.open()
        try:
            other.send(DBC.encode(OdomPose(1.0, 2.0, 0.5)))
            other.send(can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b"\x01"))
            other.send(DBC.encode(OdomTwist(0.1, 0.0, 3)))
            for _ in range(200):
                if len(sink.frames) == 2:
                    break
                await asyncio.sleep(0.01)
        finally:
            await client.close()
            other.shutdown()
        assert sink.frames == [OdomPose(1.0, 2.0, 0.5), OdomTwist(0.1, 0.0, 3)]
        assert client.counters.malformed == {"unknown_id": 1}
        assert not client.is_open

    run(main(), WallClock())


def test_poll_reader_sorts_frames_errors_and_garbage(channel: str) -> None:
    async def main() -> None:
        sink = Sink()
        client = CanBusClient(BusConfig(channel=channel), DBC, sink)
        other = can.Bus(interface="virtual", channel=channel)
        await client.open(reader="poll")
        try:
            other.send(can.Message(arbitration_id=0x040, is_error_frame=True, dlc=8, data=bytes(8)))
            other.send(can.Message(arbitration_id=0x200, is_extended_id=False, data=b"\x00"))
            other.send(DBC.encode(OdomPose(0.0, 0.0, 0.0)))
            await asyncio.sleep(0.05)
        finally:
            await client.close()
            other.shutdown()
        assert sink.frames == [OdomPose(0.0, 0.0, 0.0)]
        assert [describe_error_frame(m) for m in sink.error_frames] == ["bus-off"]
        assert client.counters.malformed == {"bad_dlc": 1}
        assert client.counters.received == 3 and client.counters.decoded == 1

    run(main(), VirtualClock())


def test_a_listener_bug_does_not_stop_the_reader(
    channel: str, caplog: pytest.LogCaptureFixture
) -> None:
    async def main() -> None:
        sink = Raising()
        client = CanBusClient(BusConfig(channel=channel), DBC, sink)
        other = can.Bus(interface="virtual", channel=channel)
        await client.open(reader="poll")
        try:
            for i in range(3):
                other.send(DBC.encode(OdomTwist(0.0, 0.0, i)))
            await asyncio.sleep(0.05)
        finally:
            await client.close()
            other.shutdown()
        assert len(sink.frames) == 3

    with caplog.at_level(logging.ERROR):
        run(main(), VirtualClock())
    assert any("error handling 0x201" in r.getMessage() for r in caplog.records)


def test_driver_error_reaches_the_listener_and_sending_fails(channel: str) -> None:
    async def main() -> None:
        sink = Sink()
        client = CanBusClient(BusConfig(channel=channel, reopen_period=None), DBC, sink)
        await client.open(reader="poll")
        assert client.bus is not None
        client.bus.shutdown()  # the interface vanishes under the reader
        await asyncio.sleep(0.05)
        with pytest.raises(BusSendError, match=f"CAN bus error on virtual:{channel}"):
            client.send_frame(OdomPose(0.0, 0.0, 0.0))
        await client.close()
        assert client.counters.bus_errors >= 1 and client.counters.send_errors == 1
        assert sink.bus_errors and "closed bus" in str(sink.bus_errors[0])
        with pytest.raises(BusSendError, match="not open"):
            client.send_frame(OdomPose(0.0, 0.0, 0.0))

    run(main(), VirtualClock())


# python-can's Notifier thread re-raises the driver error after reporting it.
@pytest.mark.filterwarnings("ignore::pytest.PytestUnhandledThreadExceptionWarning")
@pytest.mark.parametrize("reader", ["poll", "notifier"])
def test_interface_is_reopened_after_a_driver_error(channel: str, reader: str) -> None:
    async def main() -> None:
        sink = Sink()
        client = CanBusClient(BusConfig(channel=channel, reopen_period=0.2), DBC, sink)
        other = can.Bus(interface="virtual", channel=channel)
        await client.open(reader=reader)  # type: ignore[arg-type]
        try:
            assert client.bus is not None
            client.bus.shutdown()
            for _ in range(100):
                if sink.bus_errors:
                    break
                await asyncio.sleep(0.01)
            assert sink.bus_errors and client.reopening and not client.is_open
            with pytest.raises(BusSendError, match="not open"):
                client.send_frame(OdomPose(0.0, 0.0, 0.0))
            for _ in range(100):
                if client.is_open:
                    break
                await asyncio.sleep(0.01)
            assert client.counters.reopens == 1 and not client.reopening
            other.send(DBC.encode(OdomPose(3.0, 2.0, 1.0)))
            for _ in range(100):
                if sink.frames:
                    break
                await asyncio.sleep(0.01)
            assert sink.frames == [OdomPose(3.0, 2.0, 1.0)]
        finally:
            await client.close()
            other.shutdown()

    run(main(), VirtualClock() if reader == "poll" else WallClock())


def test_file_descriptor_reader_turns_a_failing_socket_into_one_bus_error() -> None:
    buses: list[SocketPairBus] = []

    def factory(**kwargs: Any) -> can.BusABC:
        buses.append(SocketPairBus(kwargs["channel"]))
        return buses[-1]

    async def main() -> None:
        sink = Sink()
        client = CanBusClient(
            BusConfig(interface="pair", channel="p0", reopen_period=0.5),
            DBC,
            sink,
            bus_factory=factory,
        )
        await client.open(reader="notifier")
        try:
            buses[0].inject(DBC.encode(OdomPose(1.0, 0.0, 0.0)))
            await asyncio.sleep(0.01)
            assert sink.frames == [OdomPose(1.0, 0.0, 0.0)]
            assert threading.active_count() == threads_before  # no reader thread
            calls = buses[0].recv_calls
            buses[0].fail(can.CanOperationError("Network is down"))
            await asyncio.sleep(0.2)
            # One error, and the dead socket is no longer watched (no busy loop).
            assert len(sink.bus_errors) == 1 and buses[0].recv_calls == calls + 1
            await asyncio.sleep(0.5)
            assert client.counters.reopens == 1 and len(buses) == 2
            buses[1].inject(DBC.encode(OdomPose(2.0, 0.0, 0.0)))
            await asyncio.sleep(0.01)
            assert sink.frames[-1] == OdomPose(2.0, 0.0, 0.0)
        finally:
            await client.close()

    threads_before = threading.active_count()
    run(main(), VirtualClock())


def test_socketcan_bitrate_is_not_silently_assumed(caplog: pytest.LogCaptureFixture) -> None:
    """SocketcanBus ignores ``bitrate``; the client says the kernel's rate applies."""

    def factory(**kwargs: Any) -> can.BusABC:
        return SocketPairBus(kwargs["channel"])

    async def main() -> None:
        config = BusConfig(interface="socketcan", channel="can0", bitrate=500_000, reader="poll")
        client = CanBusClient(config, DBC, Sink(), bus_factory=factory)
        with caplog.at_level(logging.WARNING):
            await client.open()
        await client.close()

    run(main(), VirtualClock())
    [warning] = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert "socketcan:can0: bitrate 500000 is not applied" in warning
    assert "ip link set can0 type can bitrate" in warning


def test_unknown_interface_is_a_clear_error() -> None:
    async def main() -> None:
        client = CanBusClient(BusConfig(interface="nosuchcan", channel="can0"), DBC, Sink())
        with pytest.raises(BusOpenError, match="cannot open CAN bus nosuchcan:can0"):
            await client.open()
        assert not client.is_open

    run(main(), VirtualClock())


def test_frames_are_described_for_logs() -> None:
    assert (
        describe_frame(can.Message(arbitration_id=0x201, is_extended_id=False, data=b"\x01\xab"))
        == "0x201 [2] 01 ab"
    )
    assert (
        describe_frame(can.Message(arbitration_id=0x201, is_extended_id=True, data=b""))
        == "0x00000201 [0]"
    )
    assert describe_error_frame(can.Message(arbitration_id=0x0A0, is_error_frame=True)) == (
        "no ACK on transmission, bus error"
    )
    # SocketCAN puts the controller's state in data[1] (linux/can/error.h, CAN_ERR_CRTL_*)
    passive = can.Message(arbitration_id=0x004, is_error_frame=True, data=b"\x00\x30" + bytes(6))
    assert describe_error_frame(passive) == (
        "controller problem (RX error-passive, TX error-passive)"
    )
    bare = can.Message(arbitration_id=0x004, is_error_frame=True)
    assert describe_error_frame(bare) == "controller problem"


@settings(max_examples=300, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from([0x010, 0x100, 0x200, 0x201, 0x300, 0x080, 0x7FF]),
            st.binary(max_size=8),
            st.booleans(),
            st.sampled_from(["data", "remote", "error"]),
        ),
        max_size=30,
    )
)
def test_any_frames_only_count_or_update_the_monitor(
    frames: list[tuple[int, bytes, bool, str]],
) -> None:
    """Whatever arrives, the adapter's monitor never raises and counts add up."""
    monitor = BaseMonitor(VirtualClock(), "virtual:fuzz")
    client = CanBusClient(BusConfig(channel="fuzz"), DBC, monitor)
    for frame_id, data, extended, kind in frames:
        msg = can.Message(
            arbitration_id=frame_id,
            is_extended_id=extended,
            data=data,
            is_remote_frame=kind == "remote",
            is_error_frame=kind == "error",
            dlc=len(data),
        )
        client.dispatch(msg)
    counters = client.counters
    assert counters.received == len(frames)
    assert counters.decoded + counters.error_frames + counters.malformed_total == len(frames)
    assert monitor.error_frames == counters.error_frames
