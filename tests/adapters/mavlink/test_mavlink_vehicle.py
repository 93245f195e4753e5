"""The asyncio vehicle client on its own: links, acknowledgements, faults."""

from __future__ import annotations

import asyncio
import socket

import pytest
from mavlink_support import SPEEDUP
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from plansys_bridge_adapters.mavlink.errors import (
    CommandRefused,
    CommandTimeout,
    LinkError,
    VehicleFault,
)
from plansys_bridge_adapters.mavlink.vehicle import LinkSettings, MavlinkVehicle, _device
from pymavlink.dialects.v20 import ardupilotmega as ml

FAST = LinkSettings(heartbeat_timeout=0.5, command_timeout=0.2, command_retries=2,
                    connect_timeout=2.0)


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


async def arm_guided(v: MavlinkVehicle) -> None:
    await v.connect()
    await v.set_mode("GUIDED")
    await v.wait_ekf(10)
    await v.arm(5)


@pytest.mark.parametrize("peer", [False, True], ids=["udpout", "udpin"])
def test_udp_links_both_ways(peer: bool) -> None:
    out = ("127.0.0.1", free_udp_port()) if peer else None
    with VehicleDouble("rover", speedup=SPEEDUP, ekf_delay=2.0, transport="udp",
                       peer=out) as double:
        v = MavlinkVehicle(double.url, FAST)

        async def main() -> None:
            try:
                await arm_guided(v)
            finally:
                await v.close()

        asyncio.run(main())
        assert double.url.startswith("udpin:" if peer else "udpout:")
        assert v.model == "rover"
        assert double.state()["armed"]


def test_telemetry_cache_fills_after_connect(copter: VehicleDouble) -> None:
    v = MavlinkVehicle(copter.url, FAST)

    async def main() -> None:
        try:
            await v.connect()
            await v.wait_position(2)
            await v.wait_for(lambda: v.telemetry.battery_remaining is not None, 2, "battery")
            await v.wait_ekf(5)
            await v.wait_home(2)
        finally:
            await v.close()

    asyncio.run(main())
    t = v.telemetry
    assert t.position is not None and t.position.alt == pytest.approx(0.0)
    assert t.home is not None and t.home.alt == pytest.approx(584.0)
    assert t.battery_remaining == 100.0
    assert v.mode == "STABILIZE" and v.model == "copter"
    assert {"HEARTBEAT", "COMMAND_LONG"} <= set(copter.received)


def test_refusal_quotes_the_vehicle_and_arming_retries_until_timeout() -> None:
    with VehicleDouble("copter", speedup=1.0, ekf_delay=1e6) as double:
        v = MavlinkVehicle(double.url, FAST)
        errors: list[Exception] = []

        async def main() -> None:
            try:
                await v.connect()
                try:
                    await v.arm(timeout=0.5, retry_period=0.1)
                except CommandRefused as exc:
                    errors.append(exc)
            finally:
                await v.close()

        asyncio.run(main())
        [err] = errors
        assert str(err) == (f"{double.url}: arming refused (MAV_RESULT_FAILED): still refused "
                            "after 0.5 s: PreArm: Need Position Estimate")
        arms = [c for c in double.sim.commands_seen if c == ml.MAV_CMD_COMPONENT_ARM_DISARM]
        assert len(arms) >= 3


def test_unanswered_command_times_out_naming_it(copter: VehicleDouble) -> None:
    v = MavlinkVehicle(copter.url, FAST)
    errors: list[Exception] = []

    async def main() -> None:
        try:
            await v.connect()
            copter.drop_link(1000.0)
            try:
                await v.command(ml.MAV_CMD_DO_SET_MODE, 1, 4)
            except CommandTimeout as exc:
                errors.append(exc)
        finally:
            await v.close()

    asyncio.run(main())
    assert [str(e) for e in errors] == [
        f"{copter.url}: MAV_CMD_DO_SET_MODE: no COMMAND_ACK after 2 tries (0.2 s each)"
    ]


def test_closed_link_ends_supervised_work(copter: VehicleDouble) -> None:
    v = MavlinkVehicle(copter.url, FAST)
    errors: list[Exception] = []

    async def main() -> None:
        try:
            await v.connect()
            work = asyncio.ensure_future(v.supervise(asyncio.sleep(10)))
            await asyncio.sleep(0.05)
            await asyncio.get_running_loop().run_in_executor(None, copter.stop)
            try:
                await work
            except LinkError as exc:
                errors.append(exc)
            assert not v.connected
        finally:
            await v.close()

    asyncio.run(main())
    assert [str(e) for e in errors] == [f"{copter.url}: link closed by the vehicle"]


def test_mode_change_we_asked_for_is_not_a_fault(copter: VehicleDouble) -> None:
    v = MavlinkVehicle(copter.url, FAST)
    outcome: list[object] = []

    async def main() -> None:
        try:
            await arm_guided(v)

            async def work() -> str:
                await v.set_mode("LOITER")
                await v.set_mode("GUIDED")
                await asyncio.sleep(0.1)
                return "ok"

            outcome.append(await v.supervise(work()))
            copter.change_mode("ALT_HOLD")
            try:
                await v.supervise(asyncio.sleep(5))
            except VehicleFault as exc:
                outcome.append(str(exc))
        finally:
            await v.close()

    asyncio.run(main())
    assert outcome == ["ok", f"{copter.url}: mode changed to ALT_HOLD by someone else "
                             "(expected GUIDED)"]


def test_unexpected_disarm_is_a_fault(copter: VehicleDouble) -> None:
    v = MavlinkVehicle(copter.url, FAST)
    errors: list[str] = []

    async def main() -> None:
        try:
            await arm_guided(v)
            v.expect_armed = True
            try:
                # no take-off: the copter disarms itself after DISARM_DELAY
                await v.supervise(asyncio.sleep(10))
            except VehicleFault as exc:
                errors.append(str(exc))
        finally:
            await v.close()

    asyncio.run(main())
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
