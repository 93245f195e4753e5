"""CAN adapter: codec cost, frame latency, how fast moves run, how fast faults end them.

* codec: typed encode + decode of each mobile-base frame through cantools (µs/frame);
* latency: a frame sent on a python-can ``virtual`` bus until the adapter's listener
  has it decoded, for both readers (``notifier``: python-can's Notifier thread and
  AsyncBufferedReader; ``poll``: recv(0) on the loop every ``poll_period``), on the
  wall clock: median and 99th percentile in ms;
* moves: the CAN performer driving the base double through an auction on the
  virtual clock, dock -> kitchen -> bedroom -> dock: mission seconds, wall seconds,
  x real time, frames on the bus per wall second;
* faults: mission seconds from injecting each fault to the action's FINISH (virtual
  clock, so the figure is exact: it is the detection latency the settings give).

Run: ``python benchmarks/bench_can.py [--json]``
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

import can
from bench_support import percentile
from plansys_bridge_adapters.can.bus import BusConfig, CanBusClient
from plansys_bridge_adapters.can.dbc import (
    BaseState,
    BaseStatus,
    EStopCommand,
    FaultBits,
    Frame,
    MobileBaseDbc,
    OdomPose,
    OdomTwist,
    VelocityCommand,
)
from plansys_bridge_adapters.can.double import BaseDouble, BaseDoubleConfig
from plansys_bridge_adapters.can.performer import CanBasePerformer

from plansys_bridge.clock import VirtualClock, WallClock, run
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext

LOCATIONS = {
    "dock": [0.0, 0.0, 0.0],
    "kitchen": {"x": 3.0, "y": 1.0},
    "bedroom": {"x": 1.0, "y": 3.0, "yaw": 1.5708, "via": [[2.0, 2.0]]},
}


def bench_codec(rounds: int = 5000) -> dict[str, float]:
    dbc = MobileBaseDbc.load()
    frames: list[Frame] = [
        VelocityCommand(0.5, -0.2, True, 3),
        EStopCommand(True, 1),
        OdomPose(1.234, -2.5, 0.7),
        OdomTwist(0.5, 0.1, 9),
        BaseStatus(87.5, 24.6, FaultBits(), BaseState.DRIVING, 4),
    ]
    out: dict[str, float] = {}
    for frame in frames:
        start = time.perf_counter()
        for _ in range(rounds):
            dbc.decode(dbc.encode(frame))
        out[type(frame).__name__] = (time.perf_counter() - start) / rounds * 1e6
    return out


class _Stamp:
    def __init__(self) -> None:
        self.arrived: asyncio.Event = asyncio.Event()

    def on_frame(self, frame: Frame) -> None:
        self.arrived.set()

    def on_error_frame(self, msg: can.Message) -> None:
        return None

    def on_bus_error(self, exc: Exception) -> None:
        return None


def bench_latency(reader: str, samples: int = 300) -> dict[str, float]:
    channel = f"bench-latency-{reader}"

    async def main() -> list[float]:
        stamp = _Stamp()
        dbc = MobileBaseDbc.load()
        client = CanBusClient(BusConfig(channel=channel, reader=reader), dbc, stamp)  # type: ignore[arg-type]
        sender = can.Bus(interface="virtual", channel=channel)
        await client.open()
        msg = dbc.encode(OdomPose(1.0, 2.0, 0.3))
        delays: list[float] = []
        try:
            for _ in range(samples):
                stamp.arrived.clear()
                start = time.perf_counter()
                sender.send(msg)
                await stamp.arrived.wait()
                delays.append((time.perf_counter() - start) * 1e3)
                await asyncio.sleep(0.001)
        finally:
            await client.close()
            sender.shutdown()
        return delays

    delays = run(main(), WallClock())
    return {"median_ms": statistics.median(delays), "p99_ms": percentile(delays, 0.99)}


def _performer(hub: Hub, channel: str, **extra: Any) -> CanBasePerformer:
    entry = {
        "kind": "can",
        "name": "base",
        "robot": "r1",
        "actions": {"move": {"robot": 0, "destination": 2}},
        "locations": LOCATIONS,
        "bus": {"interface": "virtual", "channel": channel},
        **extra,
    }
    [performer] = CanBasePerformer.from_config(entry, PerformerContext(hub=hub, clock=hub.clock))
    assert isinstance(performer, CanBasePerformer)
    return performer


def bench_moves() -> dict[str, float]:
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)
    channel = "bench-moves"

    async def main() -> tuple[float, int, int]:
        await hub.start()
        async with BaseDouble(clock, BusConfig(channel=channel)) as base:
            performer = _performer(hub, channel)
            async with performer:
                start = clock.now()
                for destination in ("kitchen", "bedroom", "dock"):
                    outcome = await ActionClient(hub, "move", ["r1", "x", destination]).run()
                    assert outcome.success, outcome.status
                mission = clock.now() - start
            frames = performer.client.counters.received + base.client.counters.received
        await hub.close()
        return mission, frames, base.counters.commands

    wall = time.perf_counter()
    mission, frames, commands = run(main(), clock)
    wall = time.perf_counter() - wall
    return {
        "mission_s": mission,
        "wall_s": wall,
        "x_real_time": mission / wall,
        "frames": frames,
        "frames_per_wall_s": frames / wall,
        "commands": commands,
    }


FAULTS: dict[str, Callable[[BaseDouble], None]] = {
    "silence": lambda b: b.silence(),
    "frozen heartbeat": lambda b: b.freeze_heartbeat(),
    "motor fault": lambda b: b.set_faults(motor=True),
    "e-stop button": lambda b: b.press_estop(),
    "error frame": lambda b: b.send_error_frames(1),
}


def bench_faults() -> dict[str, float]:
    out: dict[str, float] = {}
    for i, (name, inject) in enumerate(FAULTS.items()):
        clock = VirtualClock()
        hub = Hub(InProcessTransport(), clock)
        channel = f"bench-fault-{i}"

        async def main(
            inject: Callable[[BaseDouble], None] = inject,
            hub: Hub = hub,
            clock: VirtualClock = clock,
            channel: str = channel,
        ) -> float:
            await hub.start()
            double = BaseDouble(clock, BusConfig(channel=channel), BaseDoubleConfig())
            async with double as base, _performer(hub, channel):
                task = asyncio.get_running_loop().create_task(
                    ActionClient(hub, "move", ["r1", "dock", "kitchen"]).run()
                )
                await clock.sleep(2.0)
                inject(base)
                start = clock.now()
                outcome = await task
                assert not outcome.success
                latency = clock.now() - start
            await hub.close()
            return latency

        out[name] = run(main(), clock)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    results = {
        "codec_us_per_round_trip": bench_codec(),
        "latency_notifier": bench_latency("notifier"),
        "latency_poll": bench_latency("poll"),
        "moves_virtual_clock": bench_moves(),
        "fault_to_finish_mission_s": bench_faults(),
    }
    if args.json:
        json.dump(results, sys.stdout, indent=2)
        print()
        return 0
    for section, values in results.items():
        print(section)
        for key, value in values.items():
            print(
                f"  {key:24s} {value:10.3f}"
                if isinstance(value, float)
                else f"  {key:24s} {value:10d}"
            )
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    sys.exit(main())
