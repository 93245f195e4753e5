"""The asyncio vehicle client on its own: links, acknowledgements, faults."""

from __future__ import annotations

import asyncio
import os
from collections.abc import Awaitable, Callable

import pytest
from mavlink_support import SPEEDUP, free_port
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from plansys_bridge_adapters.mavlink.errors import (
    CommandRefused,
    CommandTimeout,
    LinkError,
    VehicleFault,
)
from plansys_bridge_adapters.mavlink.link import MavlinkLink, _device
from plansys_bridge_adapters.mavlink.vehicle import LinkSettings, MavlinkVehicle
from pymavlink.dialects.v20 import ardupilotmega as ml

FAST = LinkSettings(
    heartbeat_timeout=0.5, command_timeout=0.2, command_retries=2, connect_timeout=2.0
)


def with_vehicle(url: str, body: Callable[[MavlinkVehicle], Awaitable[None]]) -> MavlinkVehicle:
    """Connect a client to ``url``, run ``body`` with it, always close it."""
    v = MavlinkVehicle(url, FAST)

    async def main() -> None:
        try:
            await v.connect()
            await body(v)
        finally:
            await v.close()

    asyncio.run(main())
    return v


async def arm_guided(v: MavlinkVehicle) -> None:
    # ArduPilot's order: a mode set before the EKF has a position is lost at boot
    await v.wait_ekf(10)
    await v.set_mode("GUIDED")
    await v.arm(5)


async def error_of(work: Awaitable[object], kind: type[Exception] = Exception) -> str:
    """The message of the ``kind`` error ``work`` raises (the test fails if none)."""
    with pytest.raises(kind) as info:
        await work
    return str(info.value)


@pytest.mark.parametrize("peer", [False, True], ids=["udpout", "udpin"])
def test_udp_links_both_ways(peer: bool) -> None:
    out = ("127.0.0.1", free_port("udp")) if peer else None
    with VehicleDouble(
        "rover", speedup=SPEEDUP, ekf_delay=2.0, transport="udp", peer=out
    ) as double:
        v = with_vehicle(double.url, arm_guided)
        assert double.url.startswith("udpin:" if peer else "udpout:")
        assert v.model == "rover"
        assert double.state()["armed"]


def test_telemetry_cache_fills_after_connect(
    copter: VehicleDouble, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("MAVLINK20", raising=False)

    async def body(v: MavlinkVehicle) -> None:
        await v.wait_position(2)
        await v.wait_for(lambda: v.telemetry.battery_remaining is not None, 2, "battery")
        await v.wait_ekf(5)
        await v.wait_home(2)

    v = with_vehicle(copter.url, body)
    t = v.telemetry
    assert t.position is not None and t.position.alt == pytest.approx(0.0)
    assert t.home is not None and t.home.alt == pytest.approx(584.0)
    assert t.battery_remaining == 100.0
    assert v.mode == "STABILIZE" and v.model == "copter"
    assert {"HEARTBEAT", "COMMAND_LONG"} <= set(copter.received)
    # the link spoke MAVLink 2 without switching pymavlink's process-wide dialect
    assert "MAVLINK20" not in os.environ


def test_refusal_quotes_the_vehicle_and_arming_retries_until_timeout() -> None:
    errors: list[str] = []

    async def body(v: MavlinkVehicle) -> None:
        errors.append(await error_of(v.arm(timeout=0.5, retry_period=0.1), CommandRefused))

    with VehicleDouble("copter", speedup=1.0, ekf_delay=1e6) as double:
        with_vehicle(double.url, body)
        arms = [c for c in double.sim.commands_seen if c == ml.MAV_CMD_COMPONENT_ARM_DISARM]
    assert errors == [
        f"{double.url}: arming refused (MAV_RESULT_FAILED): still refused "
        "after 0.5 s: Arm: Need Position Estimate"
    ]
    assert len(arms) >= 3


def test_unanswered_command_times_out_naming_it(copter: VehicleDouble) -> None:
    errors: list[str] = []

    async def body(v: MavlinkVehicle) -> None:
        copter.drop_link(1000.0)
        errors.append(await error_of(v.command(ml.MAV_CMD_DO_SET_MODE, 1, 4), CommandTimeout))

    with_vehicle(copter.url, body)
    assert errors == [
        f"{copter.url}: MAV_CMD_DO_SET_MODE: no COMMAND_ACK after 2 tries (0.2 s each)"
    ]


@pytest.mark.parametrize("reader", ["loop", "thread"])
def test_closed_link_ends_supervised_work(
    copter: VehicleDouble, reader: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    if reader == "thread":  # a link without a file descriptor (a serial port on Windows)
        monkeypatch.setattr(MavlinkLink, "_descriptor", lambda self: None)
    errors: list[str] = []

    async def body(v: MavlinkVehicle) -> None:
        work = asyncio.ensure_future(v.supervise(asyncio.sleep(10)))
        await asyncio.sleep(0.05)
        await asyncio.get_running_loop().run_in_executor(None, copter.stop)
        errors.append(await error_of(work, LinkError))
        assert not v.connected
        assert (v._link._reader is not None) == (reader == "thread")

    with_vehicle(copter.url, body)
    assert errors == [f"{copter.url}: link closed by the vehicle"]


def test_mode_change_we_asked_for_is_not_a_fault(copter: VehicleDouble) -> None:
    outcome: list[object] = []

    async def body(v: MavlinkVehicle) -> None:
        await arm_guided(v)

        async def work() -> str:
            await v.set_mode("LOITER")
            await v.set_mode("GUIDED")
            await asyncio.sleep(0.1)
            return "ok"

        outcome.append(await v.supervise(work()))
        copter.change_mode("ALT_HOLD")
        outcome.append(await error_of(v.supervise(asyncio.sleep(5)), VehicleFault))

    with_vehicle(copter.url, body)
    assert outcome == [
        "ok",
        f"{copter.url}: mode changed to ALT_HOLD by someone else (expected GUIDED)",
    ]


def test_unexpected_disarm_is_a_fault(copter: VehicleDouble) -> None:
    errors: list[str] = []

    async def body(v: MavlinkVehicle) -> None:
        await arm_guided(v)
        v.expect_armed = True
        # no take-off: the copter disarms itself after DISARM_DELAY
        errors.append(await error_of(v.supervise(asyncio.sleep(10)), VehicleFault))

    with_vehicle(copter.url, body)
    assert len(errors) == 1
    assert errors[0].startswith(f"{copter.url}: disarmed unexpectedly (vehicle said: ")
    assert "Disarming motors" in errors[0]


@pytest.mark.parametrize(
    ("url", "device", "options"),
    [
        ("tcp:127.0.0.1:5760", "tcp:127.0.0.1:5760", {"retries": 0}),
        ("udpin:0.0.0.0:14550", "udpin:0.0.0.0:14550", {}),
        ("serial:/dev/ttyUSB0:57600", "/dev/ttyUSB0", {"baud": 57600}),
        ("/dev/ttyACM0", "/dev/ttyACM0", {"baud": 115200}),
    ],
)
def test_connection_strings(url: str, device: str, options: dict[str, int]) -> None:
    assert _device(url) == (device, options)


@pytest.mark.parametrize("url", ["tcp:localhost", "udp:host:port", "serial:"])
def test_bad_connection_strings_name_the_url(url: str) -> None:
    with pytest.raises(LinkError, match=f"^{url}: "):
        _device(url)
