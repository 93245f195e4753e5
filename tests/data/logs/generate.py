"""Write the small flight and CAN logs the replay tests and demos use.

    python tests/data/logs/generate.py tests/data/logs     # and: ... bags/logs

CAN: the project's base double (``plansys_bridge_adapters.can.double``) is driven
from dock (0, 0) to kitchen (3, 1) by the CAN performer on python-can's virtual bus,
on the virtual clock, starting at 80.3 % battery, so BASE_Status.BatteryPercent falls
below 80 % on the way; every frame on the bus is written with python-can's own
writers (CanutilsLogWriter ``base_r2d2.log``, ASCWriter ``base_r2d2.asc``,
BLFWriter ``base_r2d2.blf``), the base's frames as received, the commands as sent.

MAVLink: ``copter1.tlog`` is written with pymavlink's own encoder the way
``mavutil``'s ``.tlog`` logger stores it (an 8-byte big-endian microsecond stamp
before each packet): an ArduCopter-like vehicle (system 1, component 1) taking off
at the pad, flying north to the field and back, its battery falling below 25 % at t=45 s,
returning (RTL) and landing; HEARTBEAT 1 Hz, GLOBAL_POSITION_INT 5 Hz,
SYS_STATUS and BATTERY_STATUS 1 Hz.
"""

from __future__ import annotations

import asyncio
import struct
import sys
from pathlib import Path

import can
from plansys_bridge_adapters.can.bus import BusConfig
from plansys_bridge_adapters.can.double import BaseDouble, BaseDoubleConfig
from plansys_bridge_adapters.can.performer import CanBasePerformer
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.goal import ActionGoal

PLANNER_IDS = {0x010, 0x100}  # BASE_EStopCmd, BASE_VelocityCmd: sent by the planner side


async def _record_can(out: Path) -> None:
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)
    await hub.start()
    channel = "generate-can-log"
    base = BaseDouble(
        clock,
        BusConfig(interface="virtual", channel=channel),
        BaseDoubleConfig(battery_percent=80.3, odom_rate=20.0, status_rate=5.0),
    )
    await base.start()
    tap = can.Bus(interface="virtual", channel=channel)
    frames: list[can.Message] = []

    async def listen() -> None:
        while True:
            msg = tap.recv(0)
            while msg is not None:
                msg.timestamp = clock.now()
                msg.is_rx = msg.arbitration_id not in PLANNER_IDS
                msg.channel = 0
                frames.append(msg)
                msg = tap.recv(0)
            await asyncio.sleep(0.005)

    listener = asyncio.get_running_loop().create_task(listen())
    entry = {
        "kind": "can",
        "name": "base_r2d2",
        "robot": "r2d2",
        "actions": {"move": {"robot": 0, "destination": 2}},
        "locations": {"dock": [0.0, 0.0, 0.0], "kitchen": {"x": 3.0, "y": 1.0}},
        "bus": {"interface": "virtual", "channel": channel},
    }
    [performer] = CanBasePerformer.from_config(entry, PerformerContext(hub=hub, clock=clock))
    await performer.start()
    await clock.sleep(0.5)
    goal = ActionGoal("move", ("r2d2", "dock", "kitchen"), "generate")
    performer.goal = goal  # as if it had won the auction for it
    await performer.execute(goal)
    await clock.sleep(1.0)
    listener.cancel()
    await performer.stop()
    await base.stop()
    tap.shutdown()
    await hub.close()
    for name, writer in (
        ("base_r2d2.log", can.CanutilsLogWriter),
        ("base_r2d2.asc", can.ASCWriter),
        ("base_r2d2.blf", can.BLFWriter),
    ):
        log = writer(str(out / name))
        for msg in frames:
            log.on_message_received(msg)
        log.stop()
    print(f"{len(frames)} CAN frames, {frames[-1].timestamp - frames[0].timestamp:.1f} s")


def _write_tlog(path: Path) -> None:
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    home_lat, home_lon = -353632610, 1491652300
    rows: list[tuple[float, bytes]] = []
    guided, rtl, land = 4, 6, 9

    def put(t: float, msg: object) -> None:
        rows.append((t, msg.pack(mav)))  # type: ignore[attr-defined]

    for step in range(0, 901):  # 90 s at 10 Hz
        t = step / 10.0
        # the flight: climb 0-10 s, north to the field (100 m) by 40 s, back south
        # in GUIDED; the battery falls below 25 % at 45 s and the vehicle switches to
        # RTL (home by 70 s), then lands 70-85 s
        if t < 10:
            north, alt, mode = 0.0, t, guided
        elif t < 40:
            north, alt, mode = (t - 10) / 30 * 100, 10.0, guided
        elif t < 70:
            north, alt, mode = 100 - (t - 40) / 30 * 100, 10.0, guided if t < 45 else rtl
        else:
            north, alt, mode = 0.0, max(0.0, 10 - (t - 70) / 15 * 10), land
        armed = t < 86
        battery = max(0, round(60 - t * 0.8))  # 60 % at take-off, 24 % at t=45 s
        if step % 10 == 0:
            base_mode = 0x01 | (0x80 if armed else 0) | 0x08
            put(t, mavlink2.MAVLink_heartbeat_message(2, 3, base_mode, mode, 4, 3))
            put(
                t,
                mavlink2.MAVLink_sys_status_message(
                    0, 0, 0, 500, 11100 + battery * 10, 1500, battery, 0, 0, 0, 0, 0, 0
                ),
            )
            put(
                t,
                mavlink2.MAVLink_battery_status_message(
                    0, 0, 1, 3000, [3800] * 3 + [65535] * 7, 1500, 1000, 5000, battery
                ),
            )
        if step % 2 == 0:
            lat = home_lat + int(north / 111319.5 * 1e7)
            put(
                t,
                mavlink2.MAVLink_global_position_int_message(
                    int(t * 1000),
                    lat,
                    home_lon,
                    int((584 + alt) * 1000),
                    int(alt * 1000),
                    0,
                    0,
                    0,
                    0,
                ),
            )
    start_us = 1_700_000_000_000_000
    with path.open("wb") as f:
        for t, packet in rows:
            f.write(struct.pack(">Q", start_us + round(t * 1e6)) + packet)
    print(f"{len(rows)} MAVLink messages, {rows[-1][0]:.1f} s -> {path}")


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    run(_record_can(out), VirtualClock())
    _write_tlog(out / "copter1.tlog")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent))
