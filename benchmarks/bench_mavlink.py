"""MAVLink adapter: command latency, telemetry rate, mission speed, fault detection.

* commands: MAV_CMD_SET_MESSAGE_INTERVAL sent by the asyncio client until its
  COMMAND_ACK is matched, against the vehicle double over TCP and UDP loopback
  (median and 99th percentile, ms);
* telemetry: GLOBAL_POSITION_INT requested at 10 Hz of vehicle time, received per
  wall second at each speedup (the double runs on the wall clock times speedup);
* mission: take off, two legs, land through the hub's auction, wall seconds at each
  speedup, with the vehicle's simulated seconds next to it;
* faults: wall milliseconds from injecting a fault into the double to the action's
  FINISH(success=false) at the executor side (heartbeat loss: timeout set to 0.5 s).

Run: ``python benchmarks/bench_mavlink.py [--json]``
"""

from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bench_support import percentile
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from plansys_bridge_adapters.mavlink.performer import MavlinkPerformer
from plansys_bridge_adapters.mavlink.vehicle import LinkSettings, MavlinkVehicle
from pymavlink.dialects.v20 import ardupilotmega as ml

from plansys_bridge.clock import WallClock
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext

REPO_CONFIGS = Path(__file__).resolve().parents[1] / "configs"
POLICY = AuctionPolicy(retry_period=0.2, liveness_timeout=3.0)


async def _command_latency(url: str, n: int) -> list[float]:
    v = MavlinkVehicle(url, LinkSettings(telemetry_hz={}))
    await v.connect()
    try:
        out = []
        for _ in range(n):
            t = time.perf_counter()
            await v.command(
                ml.MAV_CMD_SET_MESSAGE_INTERVAL, ml.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 100_000
            )
            out.append((time.perf_counter() - t) * 1000)
        return out
    finally:
        await v.close()


def commands(n: int = 300) -> dict[str, Any]:
    result = {}
    for transport in ("tcp", "udp"):
        kind: Any = transport
        with VehicleDouble("copter", speedup=1.0, transport=kind) as double:
            ms = asyncio.run(_command_latency(double.url, n))
        result[transport] = {"median_ms": statistics.median(ms), "p99_ms": percentile(ms, 0.99)}
    return result


async def _telemetry_rate(url: str, seconds: float) -> float:
    v = MavlinkVehicle(url, LinkSettings(telemetry_hz={"GLOBAL_POSITION_INT": 10.0}))
    count = 0

    def on(msg: Any) -> None:
        nonlocal count
        count += msg.get_type() == "GLOBAL_POSITION_INT"

    await v.connect()
    v.add_listener(on)
    try:
        await asyncio.sleep(seconds)
    finally:
        await v.close()
    return count / seconds


def telemetry(speedups: tuple[float, ...] = (1, 5, 20)) -> dict[str, float]:
    out = {}
    for s in speedups:
        with VehicleDouble("copter", speedup=s) as double:
            out[f"x{s:g}"] = asyncio.run(_telemetry_rate(double.url, 2.0))
    return out


def _config(url: str, heartbeat: float = 3.0) -> dict[str, Any]:
    return {
        "kind": "mavlink",
        "name": "uav1_performer",
        "vehicle": "uav1",
        "url": url,
        "locations": "mavlink_locations.yaml",
        "heartbeat_period": 0.2,
        "actions": {"takeoff": [], "fly": [], "land": []},
        "commands": {
            "takeoff": {"do": "takeoff", "vehicle_arg": 0, "altitude": 10},
            "fly": {"do": "goto", "vehicle_arg": 0, "target_arg": 2},
            "land": {"do": "land", "vehicle_arg": 0},
        },
        "timeouts": {"heartbeat": heartbeat, "command": 0.5},
    }


async def _with_performer(url: str, body: Callable[[Hub], Any], heartbeat: float = 3.0) -> Any:
    hub = Hub(InProcessTransport(), WallClock())
    await hub.start()
    ctx = PerformerContext(hub=hub, clock=hub.clock, base_dir=REPO_CONFIGS)
    [performer] = MavlinkPerformer.from_config(_config(url, heartbeat), ctx)
    await performer.start()
    try:
        return await body(hub)
    finally:
        await performer.stop()
        await hub.close()


async def _act(hub: Hub, action: str, *args: str) -> Any:
    return await ActionClient(hub, action, args, policy=POLICY).run()


def mission(speedups: tuple[float, ...] = (5, 20, 40)) -> dict[str, dict[str, float]]:
    steps = [
        ("takeoff", "uav1", "pad"),
        ("fly", "uav1", "pad", "north_field"),
        ("fly", "uav1", "north_field", "east_field"),
        ("land", "uav1", "east_field"),
    ]
    out = {}
    for s in speedups:
        with VehicleDouble("copter", speedup=s, ekf_delay=20.0) as double:

            async def body(hub: Hub) -> None:
                for step in steps:
                    outcome = await _act(hub, *step)
                    assert outcome.success, outcome.status

            t = time.perf_counter()
            asyncio.run(_with_performer(double.url, body))
            wall = time.perf_counter() - t
            out[f"x{s:g}"] = {"wall_s": wall, "vehicle_s": double.state()["time"]}
    return out


def faults(speedup: float = 20.0) -> dict[str, float]:
    injections: dict[str, Callable[[VehicleDouble], None]] = {
        "mode_change": lambda d: d.change_mode("LOITER"),
        "failsafe": lambda d: d.failsafe("Radio"),
        "statustext_error": lambda d: d.statustext("Crash: Disarming", ml.MAV_SEVERITY_CRITICAL),
        "heartbeat_lost": lambda d: d.drop_link(1000.0),
    }
    out = {}
    for name, inject in injections.items():
        with VehicleDouble("copter", speedup=speedup, ekf_delay=2.0, cruise_speed=1.0) as double:

            async def body(
                hub: Hub, d: VehicleDouble = double, fire: Callable[[VehicleDouble], None] = inject
            ) -> float:
                assert (await _act(hub, "takeoff", "uav1", "pad")).success
                flight = asyncio.ensure_future(_act(hub, "fly", "uav1", "pad", "north_field"))
                while d.state()["north"] < 2:
                    await asyncio.sleep(0.005)
                t = time.perf_counter()
                fire(d)
                outcome = await flight
                assert not outcome.success
                return (time.perf_counter() - t) * 1000

            out[name + "_ms"] = asyncio.run(_with_performer(double.url, body, heartbeat=0.5))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    results = {
        "commands": commands(),
        "telemetry_msgs_per_s": telemetry(),
        "mission": mission(),
        "faults": faults(),
    }
    if args.json:
        json.dump(results, sys.stdout, indent=2)
        print()
        return 0
    for transport, r in results["commands"].items():
        print(
            f"COMMAND_ACK round trip {transport}: median {r['median_ms']:.2f} ms, "
            f"p99 {r['p99_ms']:.2f} ms"
        )
    for s, rate in results["telemetry_msgs_per_s"].items():
        print(f"GLOBAL_POSITION_INT at 10 Hz vehicle time, {s}: {rate:.0f} msg/s")
    for s, r in results["mission"].items():
        print(
            f"copter mission (EKF wait, take-off, 2 legs, land) {s}: "
            f"{r['wall_s']:.2f} s wall, {r['vehicle_s']:.0f} s vehicle time"
        )
    for name, ms in results["faults"].items():
        print(f"fault -> FINISH(failure) {name}: {ms:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
