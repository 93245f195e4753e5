"""A simulated differential-drive base that speaks the DBC on a python-can bus.

The double is what the adapter's tests and the virtual-bus demo talk to. It
behaves like a base controller: it decodes ``BASE_VelocityCmd`` and
``BASE_EStopCmd``, integrates unicycle kinematics under its own acceleration
limits, and sends ``BASE_OdomPose``/``BASE_OdomTwist`` at 50 Hz and
``BASE_Status`` at 10 Hz. It enforces the command watchdog (commands that stop or
repeat their alive counter while a non-zero velocity is commanded make it brake and
set the watchdog bit; after a zero command it needs no more),
honours the e-stop (command or "button"), drains its battery, and can be told to
misbehave: go silent, freeze its heartbeat counter, raise fault bits, put error
frames or garbage on the bus.

It runs on asyncio and takes all its time from a project :class:`Clock`, so on the
VirtualClock a minute of driving takes a fraction of a second and is deterministic;
with a scaled WallClock its physics run at mission speed too.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import math
import random
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import can

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.clock import Clock, WallClock
from plansys_bridge.errors import AdapterError

from .bus import BusConfig, CanBusClient
from .dbc import (
    BaseState,
    BaseStatus,
    EStopCommand,
    FaultBits,
    Frame,
    MobileBaseDbc,
    OdomPose,
    OdomTwist,
    VelocityCommand,
    normalize_angle,
)

_LOG = logging.getLogger(__name__)

_MOVING_EPS = 1e-3


@dataclass(frozen=True)
class BaseLimits:
    """What the simulated drive can do (the base's own limits, not the planner's)."""

    max_linear: float = 1.0
    max_angular: float = 2.0
    max_linear_accel: float = 1.0
    max_angular_accel: float = 3.0
    estop_decel: float = 3.0
    """Linear deceleration when braking for the e-stop or a fault (angular: 3x)."""


@dataclass
class UnicycleModel:
    """Pose and twist of a differential-drive base; velocities follow targets within limits."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    linear: float = 0.0
    angular: float = 0.0

    def step(
        self,
        dt: float,
        target_linear: float,
        target_angular: float,
        linear_accel: float,
        angular_accel: float,
    ) -> None:
        """Advance ``dt`` seconds: ramp velocities towards the targets, then move."""
        if dt <= 0:
            return
        self.linear += max(-linear_accel * dt, min(linear_accel * dt, target_linear - self.linear))
        self.angular += max(
            -angular_accel * dt, min(angular_accel * dt, target_angular - self.angular)
        )
        # Exact integration along the arc (midpoint heading is enough at 100 Hz).
        mid_yaw = self.yaw + self.angular * dt / 2
        self.x += self.linear * math.cos(mid_yaw) * dt
        self.y += self.linear * math.sin(mid_yaw) * dt
        self.yaw = normalize_angle(self.yaw + self.angular * dt)

    @property
    def moving(self) -> bool:
        return abs(self.linear) > _MOVING_EPS or abs(self.angular) > _MOVING_EPS


@dataclass(frozen=True)
class BaseDoubleConfig:
    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    limits: BaseLimits = field(default_factory=BaseLimits)
    physics_rate: float = 100.0
    odom_rate: float = 50.0
    status_rate: float = 10.0
    watchdog_timeout: float = 0.3
    battery_percent: float = 95.0
    battery_drain_idle: float = 0.01
    """Percent per second while powered."""
    battery_drain_per_metre: float = 0.2
    voltage_empty: float = 22.0
    voltage_full: float = 25.2


@dataclass
class DoubleCounters:
    commands: int = 0
    stale_commands: int = 0
    ignored_commands: int = 0
    estop_commands: int = 0
    watchdog_trips: int = 0
    error_frames_seen: int = 0


class BaseDouble:
    """The simulated base: open with :meth:`start`, close with :meth:`stop`."""

    def __init__(
        self,
        clock: Clock,
        bus: BusConfig | None = None,
        config: BaseDoubleConfig | None = None,
        dbc: MobileBaseDbc | None = None,
    ) -> None:
        self.clock = clock
        self.config = config or BaseDoubleConfig()
        self.bus_config = bus or BusConfig()
        self.model = UnicycleModel(self.config.x, self.config.y, self.config.yaw)
        self.battery = self.config.battery_percent
        self.counters = DoubleCounters()
        self.client = CanBusClient(self.bus_config, dbc or MobileBaseDbc.load(), self)
        self._target = (0.0, 0.0)
        self._last_command_time: float | None = None
        self._last_counter: int | None = None
        self._watchdog_tripped = False
        self._estop_commanded = False
        self._estop_button = False
        self._faults = FaultBits()
        self._silent_until: float | None = None
        self._heartbeat_frozen = False
        self._wheels_blocked = False
        self._odom_counter = 0
        self._heartbeat_counter = 0
        self._task: asyncio.Task[None] | None = None
        self.last_command: VelocityCommand | None = None

    # -- lifecycle -------------------------------------------------------------

    async def start(self) -> None:
        await self.client.open(reader="manual")
        self._task = asyncio.get_running_loop().create_task(self._run())

    async def stop(self) -> None:
        if self._task is not None:
            await cancel_and_wait(self._task)
            self._task = None
        await self.client.close()

    async def __aenter__(self) -> BaseDouble:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    # -- what the base reports -------------------------------------------------

    @property
    def estop_active(self) -> bool:
        return self._estop_commanded or self._estop_button

    @property
    def faults(self) -> FaultBits:
        return replace(self._faults, estop=self.estop_active, watchdog=self._watchdog_tripped)

    @property
    def state(self) -> BaseState:
        if self._faults.motor or self._faults.overcurrent:
            return BaseState.FAULT
        if self.estop_active:
            return BaseState.ESTOP
        if self._watchdog_tripped:
            return BaseState.STOPPED
        if self.model.moving or self._target != (0.0, 0.0):
            return BaseState.DRIVING
        return BaseState.IDLE

    def status_frame(self) -> BaseStatus:
        voltage = self.config.voltage_empty + (
            self.config.voltage_full - self.config.voltage_empty
        ) * (self.battery / 100.0)
        return BaseStatus(
            battery_percent=round(self.battery * 2) / 2,
            battery_voltage=round(voltage, 2),
            faults=self.faults,
            state=self.state,
            counter=self._heartbeat_counter,
        )

    # -- fault injection ---------------------------------------------------------

    def silence(self, duration: float | None = None) -> None:
        """Stop transmitting for ``duration`` seconds (None: until :meth:`speak`)."""
        self._silent_until = math.inf if duration is None else self.clock.now() + duration

    def speak(self) -> None:
        self._silent_until = None

    def freeze_heartbeat(self, frozen: bool = True) -> None:
        """Keep sending status frames but with a stuck alive counter (a hung controller)."""
        self._heartbeat_frozen = frozen

    def set_faults(self, *, motor: bool | None = None, overcurrent: bool | None = None) -> None:
        """Raise or clear drive faults; a drive fault makes the base brake."""
        self._faults = FaultBits(
            motor=self._faults.motor if motor is None else motor,
            overcurrent=self._faults.overcurrent if overcurrent is None else overcurrent,
        )
        if self._faults.any:
            self._target = (0.0, 0.0)

    def press_estop(self, pressed: bool = True) -> None:
        """The hardware e-stop button."""
        self._estop_button = pressed
        if pressed:
            self._target = (0.0, 0.0)

    def block_wheels(self, blocked: bool = True) -> None:
        """An obstacle or a jammed wheel: the base accepts commands but does not move."""
        self._wheels_blocked = blocked

    def set_battery(self, percent: float) -> None:
        self.battery = max(0.0, min(100.0, percent))

    def send_error_frames(self, count: int = 1) -> None:
        """Put CAN error frames on the bus (as a controller reports bit/CRC errors)."""
        for _ in range(count):
            self.client.send_raw(
                # As SocketCAN delivers it: the error class (0x080 bus error) in the ID.
                can.Message(
                    arbitration_id=0x080,
                    is_extended_id=False,
                    is_error_frame=True,
                    dlc=8,
                    data=bytes(8),
                )
            )

    def send_garbage(self, count: int = 20, seed: int = 0) -> list[can.Message]:
        """Send frames the adapter must reject; returns what was sent."""
        rng = random.Random(seed)
        dbc = self.client.dbc
        known = [dbc.message_for(t) for t in (OdomPose, OdomTwist, BaseStatus)]
        sent: list[can.Message] = []
        for i in range(count):
            choice = i % 5
            if choice == 0:  # unknown standard ID
                ids = {m.frame_id for m in dbc.database.messages}
                frame_id = rng.choice([n for n in range(0x7F0, 0x800) if n not in ids])
                msg = can.Message(
                    arbitration_id=frame_id,
                    is_extended_id=False,
                    data=rng.randbytes(rng.randint(0, 8)),
                )
            elif choice == 1:  # known ID, wrong length
                message = rng.choice(known)
                length = rng.choice([n for n in range(0, 9) if n != message.length])
                msg = can.Message(
                    arbitration_id=message.frame_id,
                    is_extended_id=False,
                    data=rng.randbytes(length),
                )
            elif choice == 2:  # extended ID that happens to equal a known standard one
                msg = can.Message(
                    arbitration_id=rng.choice(known).frame_id,
                    is_extended_id=True,
                    data=rng.randbytes(8),
                )
            elif choice == 3:  # remote frame
                message = rng.choice(known)
                msg = can.Message(
                    arbitration_id=message.frame_id,
                    is_extended_id=False,
                    is_remote_frame=True,
                    dlc=message.length,
                )
            else:  # status with signals outside their DBC range
                message = dbc.message_for(BaseStatus)
                data = bytearray(message.length)
                data[0] = 0xFF  # BatteryPercent 127.5 %
                data[3] = 0x0F  # BaseState 15
                msg = can.Message(
                    arbitration_id=message.frame_id, is_extended_id=False, data=bytes(data)
                )
            self.client.send_raw(msg)
            sent.append(msg)
        return sent

    # -- FrameListener -------------------------------------------------------------

    def on_frame(self, frame: Frame) -> None:
        if isinstance(frame, VelocityCommand):
            self._on_velocity(frame)
        elif isinstance(frame, EStopCommand):
            self.counters.estop_commands += 1
            self._estop_commanded = frame.engage
            if frame.engage:
                self._target = (0.0, 0.0)

    def on_error_frame(self, msg: can.Message) -> None:
        self.counters.error_frames_seen += 1

    def on_bus_error(self, exc: Exception) -> None:
        _LOG.warning("base double: bus error %s", exc)

    def _on_velocity(self, cmd: VelocityCommand) -> None:
        self.counters.commands += 1
        self.last_command = cmd
        if cmd.counter == self._last_counter:
            # A repeated alive counter is a stuck sender: it must not feed the watchdog.
            self.counters.stale_commands += 1
            return
        self._last_counter = cmd.counter
        if self.estop_active or self._faults.motor or self._faults.overcurrent:
            self.counters.ignored_commands += 1
            return
        self._last_command_time = self.clock.now()
        self._watchdog_tripped = False
        lim = self.config.limits
        if cmd.enable:
            self._target = (
                max(-lim.max_linear, min(lim.max_linear, cmd.linear)),
                max(-lim.max_angular, min(lim.max_angular, cmd.angular)),
            )
        else:
            self._target = (0.0, 0.0)

    # -- simulation loop -------------------------------------------------------------

    async def _run(self) -> None:
        cfg = self.config
        physics_period = 1.0 / cfg.physics_rate
        odom_period = 1.0 / cfg.odom_rate
        status_period = 1.0 / cfg.status_rate
        last = self.clock.now()
        next_odom = last
        next_status = last
        while True:
            await self.clock.sleep(physics_period)
            self.client.drain()
            now = self.clock.now()
            self._physics(now, now - last)
            last = now
            if self._silent_until is not None and now >= self._silent_until:
                self._silent_until = None
            transmitting = self._silent_until is None
            # A microsecond of slack: float sums of periods must not skip a physics step.
            if now >= next_odom - 1e-6:
                next_odom = max(next_odom + odom_period, now - odom_period)
                if transmitting:
                    self._send_odometry()
            if now >= next_status - 1e-6:
                next_status = max(next_status + status_period, now - status_period)
                if transmitting:
                    self._send_status()

    def _physics(self, now: float, dt: float) -> None:
        cfg, lim = self.config, self.config.limits
        if (
            self._last_command_time is not None
            and not self._watchdog_tripped
            and self._target != (0.0, 0.0)
            and now - self._last_command_time > cfg.watchdog_timeout
        ):
            self._watchdog_tripped = True
            self.counters.watchdog_trips += 1
            self._target = (0.0, 0.0)
        braking = self.estop_active or self._faults.motor or self._faults.overcurrent
        if braking:
            self._target = (0.0, 0.0)
            linear_accel, angular_accel = lim.estop_decel, lim.estop_decel * 3
        else:
            linear_accel, angular_accel = lim.max_linear_accel, lim.max_angular_accel
        x0, y0 = self.model.x, self.model.y
        if self._wheels_blocked:
            self.model.linear = self.model.angular = 0.0
            return
        self.model.step(dt, self._target[0], self._target[1], linear_accel, angular_accel)
        travelled = math.hypot(self.model.x - x0, self.model.y - y0)
        drain = cfg.battery_drain_idle * dt + cfg.battery_drain_per_metre * travelled
        self.battery = max(0.0, self.battery - drain)

    def _send(self, frame: Frame) -> None:
        if not self.client.is_open:
            return  # reopening after a bus error: a real controller's TX is down too
        try:
            self.client.send_frame(frame)
        except Exception as exc:
            # A simulated base keeps running when its transmit fails, like a real one.
            _LOG.warning("base double: cannot send %s: %s", type(frame).__name__, exc)

    def _send_odometry(self) -> None:
        m = self.model
        self._send(OdomPose(m.x, m.y, m.yaw))
        self._send(OdomTwist(m.linear, m.angular, self._odom_counter))
        self._odom_counter = (self._odom_counter + 1) % 256

    def _send_status(self) -> None:
        self._send(self.status_frame())
        if not self._heartbeat_frozen:
            self._heartbeat_counter = (self._heartbeat_counter + 1) % 256


async def serve(
    clock: Clock,
    bus: BusConfig,
    config: BaseDoubleConfig,
    dbc: MobileBaseDbc,
    duration: float | None,
) -> BaseDouble:
    """Run a base double until ``duration`` (mission seconds) passes or forever."""
    async with BaseDouble(clock, bus, config, dbc) as base:
        if duration is None:
            await asyncio.Event().wait()
        else:
            await clock.sleep(duration)
    return base


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m plansys_bridge_adapters.can.double``: a simulated base on any python-can bus.

    Useful to try the CAN performer against a virtual SocketCAN interface
    (``ip link add dev vcan0 type vcan``) from another process, without the robot.
    """
    parser = argparse.ArgumentParser(
        prog="python -m plansys_bridge_adapters.can.double",
        description="Simulated differential-drive base speaking the mobile-base DBC.",
    )
    parser.add_argument("--interface", default="socketcan", help="python-can interface")
    parser.add_argument("--channel", default="vcan0")
    parser.add_argument("--bitrate", type=int, default=None)
    parser.add_argument("--dbc", type=Path, default=None, help="DBC file (default: packaged)")
    parser.add_argument("--x", type=float, default=0.0)
    parser.add_argument("--y", type=float, default=0.0)
    parser.add_argument("--yaw", type=float, default=0.0)
    parser.add_argument("--watchdog-timeout", type=float, default=0.3)
    parser.add_argument("--battery", type=float, default=95.0, help="initial percent")
    parser.add_argument("--duration", type=float, default=None, help="seconds (default: forever)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    bus = BusConfig(interface=args.interface, channel=args.channel, bitrate=args.bitrate)
    config = BaseDoubleConfig(
        x=args.x,
        y=args.y,
        yaw=args.yaw,
        watchdog_timeout=args.watchdog_timeout,
        battery_percent=args.battery,
    )
    try:
        dbc = MobileBaseDbc.load(args.dbc)
        base = asyncio.run(serve(WallClock(), bus, config, dbc, args.duration))
    except KeyboardInterrupt:
        return 0
    except AdapterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    m = base.model
    print(f"base stopped at x={m.x:.3f} y={m.y:.3f} yaw={m.yaw:.3f}, battery {base.battery:.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
