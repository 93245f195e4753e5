"""The base double on the virtual bus: kinematics, rates, watchdog, e-stop, faults."""

from __future__ import annotations

import itertools
import math
import threading
from collections.abc import AsyncIterator, Callable, Coroutine
from contextlib import asynccontextmanager
from typing import Any

import can
import pytest
from plansys_bridge_adapters.can.bus import BusConfig, CanBusClient
from plansys_bridge_adapters.can.dbc import (
    BaseState,
    BaseStatus,
    EStopCommand,
    Frame,
    MobileBaseDbc,
    OdomPose,
    OdomTwist,
    VelocityCommand,
)
from plansys_bridge_adapters.can.double import BaseDouble, BaseDoubleConfig, BaseLimits, main

from plansys_bridge.clock import VirtualClock, run


class Recorder:
    """A bus listener that keeps what it hears with the virtual time it arrived."""

    def __init__(self, clock: VirtualClock) -> None:
        self.clock = clock
        self.frames: list[tuple[float, Frame]] = []
        self.error_frames: list[can.Message] = []
        self.bus_errors: list[Exception] = []

    def on_frame(self, frame: Frame) -> None:
        self.frames.append((self.clock.now(), frame))

    def on_error_frame(self, msg: can.Message) -> None:
        self.error_frames.append(msg)

    def on_bus_error(self, exc: Exception) -> None:
        self.bus_errors.append(exc)

    def of(self, kind: type) -> list[tuple[float, Any]]:
        return [(t, f) for t, f in self.frames if isinstance(f, kind)]

    def last(self, kind: type) -> Any:
        return self.of(kind)[-1][1]


class Driver:
    """Plays the planner side by hand: sends commands with fresh alive counters."""

    def __init__(self, client: CanBusClient) -> None:
        self.client = client
        self.counter = 0

    def velocity(
        self, linear: float, angular: float, enable: bool = True, counter: int | None = None
    ) -> None:
        if counter is None:
            self.counter = (self.counter + 1) % 16
            counter = self.counter
        self.client.send_frame(VelocityCommand(linear, angular, enable, counter))

    async def hold(
        self, clock: VirtualClock, seconds: float, linear: float, angular: float, rate: float = 20.0
    ) -> None:
        for _ in range(round(seconds * rate)):
            self.velocity(linear, angular)
            await clock.sleep(1 / rate)


@asynccontextmanager
async def base_and_driver(
    clock: VirtualClock, channel: str, config: BaseDoubleConfig | None = None
) -> AsyncIterator[tuple[BaseDouble, Driver, Recorder]]:
    bus = BusConfig(channel=channel)
    async with BaseDouble(clock, bus, config) as base:
        recorder = Recorder(clock)
        client = CanBusClient(bus, MobileBaseDbc.load(), recorder)
        await client.open(reader="poll")
        try:
            yield base, Driver(client), recorder
        finally:
            await client.close()


def run_virtual(test: Callable[[VirtualClock], Coroutine[Any, Any, None]]) -> None:
    clock = VirtualClock()
    run(test(clock), clock)


def test_drives_with_acceleration_limits_and_reports_odometry(channel: str) -> None:
    limits = BaseLimits(max_linear_accel=0.5)

    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel, BaseDoubleConfig(limits=limits)) as (
            base,
            driver,
            rec,
        ):
            await driver.hold(clock, 3.0, 0.5, 0.0)
            twists = [f for _, f in rec.of(OdomTwist)]
            # Odometry every 20 ms, ramping at 0.5 m/s^2: 10 mm/s per sample (1 mm/s resolution).
            assert [t.counter for t in twists] == [i % 256 for i in range(len(twists))]
            for a, b in itertools.pairwise(twists):
                assert b.linear - a.linear <= 0.5 * 0.02 + 0.0015
            assert twists[-1].linear == pytest.approx(0.5, abs=1e-3)
            pose = rec.last(OdomPose)
            # 1 s ramp (0.25 m) + ~2 s at 0.5 m/s.
            assert pose.x == pytest.approx(base.model.x, abs=0.02)
            assert 1.1 < pose.x < 1.3 and abs(pose.y) < 1e-3
            assert rec.last(BaseStatus).state is BaseState.DRIVING

    run_virtual(scenario)


def test_rates_50_hz_odometry_10_hz_status(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel) as (_, _driver, rec):
            start = clock.now()
            await clock.sleep(2.0)
            span = clock.now() - start
            assert len(rec.of(OdomPose)) == pytest.approx(50 * span, abs=2)
            assert len(rec.of(OdomTwist)) == len(rec.of(OdomPose))
            statuses = [f for _, f in rec.of(BaseStatus)]
            assert len(statuses) == pytest.approx(10 * span, abs=1)
            counters = [s.counter for s in statuses]
            assert counters == list(range(counters[0], counters[0] + len(counters)))
            assert statuses[-1].state is BaseState.IDLE

    run_virtual(scenario)


def test_watchdog_stops_the_base_when_commands_stop(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        config = BaseDoubleConfig(watchdog_timeout=0.3)
        async with base_and_driver(clock, channel, config) as (base, driver, rec):
            await driver.hold(clock, 1.0, 0.4, 0.2)
            assert base.model.moving
            await clock.sleep(1.5)  # commands stop
            assert not base.model.moving
            status = rec.last(BaseStatus)
            assert status.faults.watchdog and status.state is BaseState.STOPPED
            assert base.counters.watchdog_trips == 1
            driver.velocity(0.0, 0.0)  # a fresh command clears the latched bit
            await clock.sleep(0.2)
            assert not rec.last(BaseStatus).faults.watchdog

    run_virtual(scenario)


def test_repeated_alive_counter_does_not_feed_the_watchdog(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel) as (base, driver, rec):
            await driver.hold(clock, 0.5, 0.4, 0.0)
            for _ in range(30):  # a stuck sender repeating one frame
                driver.velocity(0.4, 0.0, counter=driver.counter)
                await clock.sleep(0.05)
            assert base.counters.stale_commands == 30
            assert rec.last(BaseStatus).faults.watchdog
            assert not base.model.moving

    run_virtual(scenario)


def test_estop_command_brakes_and_blocks_commands_until_released(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel) as (base, driver, rec):
            await driver.hold(clock, 1.0, 0.8, 0.0)
            driver.client.send_frame(EStopCommand(True, 1))
            await driver.hold(clock, 1.0, 0.8, 0.0)  # ignored while the e-stop is on
            assert not base.model.moving
            status = rec.last(BaseStatus)
            assert status.faults.estop and status.state is BaseState.ESTOP
            assert base.counters.ignored_commands >= 19
            driver.client.send_frame(EStopCommand(False, 2))
            await driver.hold(clock, 0.5, 0.3, 0.0)
            assert base.model.moving and not rec.last(BaseStatus).faults.estop

    run_virtual(scenario)


def test_estop_braking_is_harder_than_normal_deceleration(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        config = BaseDoubleConfig(limits=BaseLimits(max_linear_accel=0.5, estop_decel=4.0))
        async with base_and_driver(clock, channel, config) as (base, driver, _):
            await driver.hold(clock, 3.0, 1.0, 0.0)
            base.press_estop()
            await clock.sleep(0.3)  # 1.0 m/s at 4 m/s^2: stopped in 0.25 s
            assert not base.model.moving

    run_virtual(scenario)


@pytest.mark.parametrize("fault", ["motor", "overcurrent"])
def test_drive_fault_brakes_and_is_reported(channel: str, fault: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel) as (base, driver, rec):
            await driver.hold(clock, 1.0, 0.5, 0.0)
            base.set_faults(**{fault: True})
            await driver.hold(clock, 1.0, 0.5, 0.0)
            status = rec.last(BaseStatus)
            assert getattr(status.faults, fault) and status.state is BaseState.FAULT
            assert not base.model.moving

    run_virtual(scenario)


def test_battery_drains_faster_when_driving(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        config = BaseDoubleConfig(
            battery_percent=50.0, battery_drain_idle=0.1, battery_drain_per_metre=2.0
        )
        async with base_and_driver(clock, channel, config) as (base, driver, rec):
            await clock.sleep(10.0)
            idle = 50.0 - base.battery
            assert idle == pytest.approx(1.0, abs=0.05)
            before = base.battery
            await driver.hold(clock, 10.0, 0.5, 0.0)
            moving = before - base.battery
            assert moving > idle + 2 * base.model.x * 0.9
            status = rec.last(BaseStatus)
            assert status.battery_percent == pytest.approx(base.battery, abs=0.5)
            assert 22.0 < status.battery_voltage < 25.2

    run_virtual(scenario)


def test_silence_and_frozen_heartbeat(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel) as (base, _driver, rec):
            await clock.sleep(0.5)
            base.silence(1.0)
            heard = len(rec.frames)
            await clock.sleep(0.9)
            assert len(rec.frames) == heard
            await clock.sleep(0.5)
            assert len(rec.frames) > heard
            base.freeze_heartbeat()
            await clock.sleep(0.3)
            counters = {f.counter for _, f in rec.of(BaseStatus)[-3:]}
            assert len(counters) == 1

    run_virtual(scenario)


def test_error_and_garbage_frames_reach_the_bus(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel) as (base, driver, rec):
            base.send_error_frames(2)
            sent = base.send_garbage(25, seed=3)
            await clock.sleep(0.1)
            assert len(rec.error_frames) == 2
            counters = driver.client.counters
            assert counters.malformed_total == len(sent) == 25
            assert set(counters.malformed) == {"unknown_id", "bad_dlc", "remote", "out_of_range"}
            assert rec.bus_errors == []

    run_virtual(scenario)


def test_blocked_wheels_keep_the_base_still(channel: str) -> None:
    async def scenario(clock: VirtualClock) -> None:
        async with base_and_driver(clock, channel) as (base, driver, _):
            base.block_wheels()
            await driver.hold(clock, 1.0, 0.5, 0.5)
            assert (base.model.x, base.model.y, base.model.yaw) == (0.0, 0.0, 0.0)
            assert base.counters.watchdog_trips == 0
            assert math.isclose(base.model.linear, 0.0)

    run_virtual(scenario)


def test_command_line_double_serves_a_bus(channel: str, capsys: pytest.CaptureFixture[str]) -> None:
    listener = can.Bus(interface="virtual", channel=channel)
    results: list[int] = []
    thread = threading.Thread(
        target=lambda: results.append(
            main(
                ["--interface", "virtual", "--channel", channel, "--x", "1.5", "--duration", "0.3"]
            )
        ),
        name="can-double-cli",
    )
    thread.start()
    try:
        poses: list[OdomPose] = []
        dbc = MobileBaseDbc.load()
        while thread.is_alive() or not poses:
            msg = listener.recv(0.5)
            if msg is None:
                break
            frame = dbc.decode(msg)
            if isinstance(frame, OdomPose):
                poses.append(frame)
    finally:
        thread.join()
        listener.shutdown()
    assert results == [0]
    assert len(poses) >= 5 and poses[0] == OdomPose(1.5, 0.0, 0.0)
    assert "base stopped at x=1.500" in capsys.readouterr().out


def test_command_line_double_reports_a_bad_interface(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--interface", "nosuchcan", "--channel", "can9", "--duration", "0.1"]) == 1
    assert "cannot open CAN bus nosuchcan:can9" in capsys.readouterr().err
