"""Bag read and replay throughput over the real recordings, and the memory it takes.

For each pose topic of the bags in ../shared/bags (and the project's demo bag):

* read: stream every pose with :class:`BagReader` (ROS 1 -> ROS 2 conversion and
  pose extraction included): messages/s, against rosbags' AnyReader deserialising the
  same messages (peer/s and the time ratio), and "x real time" = recorded duration /
  wall time to read it;
* replay: the whole topic replayed by :class:`BagNavigationPerformer` through an
  auction on the virtual clock (feedback at 10 Hz, poses to a MissionRecorder),
  wall time and x real time. This is how fast a mission on recorded navigation
  runs offline;
* memory: tracemalloc peak while reading (Python allocations), and the process's
  peak RSS at the end (``resource.getrusage``).

Run: ``python benchmarks/bench_bag_replay.py [--bags DIR] [--json]``
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import tempfile
import time
import tracemalloc
from pathlib import Path
from typing import Any

from bench_support import BAGS
from plansys_bridge_adapters.rosbag.performer import BagNavigationPerformer
from plansys_bridge_adapters.rosbag.reader import BagReader, ros2_typestore
from plansys_bridge_adapters.rosbag.route import Route
from rosbags.highlevel import AnyReader

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.monitoring.recorder import MissionRecorder
from plansys_bridge.performers.base import PerformerContext

REPO = Path(__file__).resolve().parents[1]
SOURCES = [
    ("rl_test1.bag", "/husky_velocity_controller/odom"),
    ("rl_test3_groovy.bag", "/ardrone/odometry/raw"),
    ("amr_rosbag_demo.bag", "/location"),
    ("evo_nav2_turtlebot.mcap", "/odom"),
    ("evo_nav2_turtlebot.mcap", "/amcl_pose"),
]


def _read_all(path: Path, topic: str) -> tuple[int, float, str]:
    with BagReader(path) as bag:
        count = sum(1 for _ in bag.poses(topic))
        duration = (bag.end_ns - bag.start_ns) / 1e9
        fmt = "ROS 1" if bag.is_ros1 else "ROS 2"
    return count, duration, fmt


def _peer_read(path: Path, topic: str) -> int:
    """rosbags' AnyReader on the same topic, deserialising every message."""
    with AnyReader([path], default_typestore=ros2_typestore()) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        count = 0
        for conn, _time, raw in reader.messages(connections=conns):
            reader.deserialize(raw, conn.msgtype)
            count += 1
        return count


def bench_read(path: Path, topic: str, repeat: int = 3) -> dict[str, Any]:
    ros2_typestore()  # built once per process, not part of the measurement
    walls = []
    peers = []
    for _ in range(repeat):  # in turn with the peer, so a drifting machine hits both
        started = time.perf_counter()
        count, duration, fmt = _read_all(path, topic)
        walls.append(time.perf_counter() - started)
        started = time.perf_counter()
        _peer_read(path, topic)
        peers.append(time.perf_counter() - started)
    wall, peer = min(walls), min(peers)
    # memory in a separate pass: tracemalloc slows Python allocations down a lot
    tracemalloc.start()
    _read_all(path, topic)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {
        "bag": path.name,
        "topic": topic,
        "format": fmt,
        "messages": count,
        "size_mb": round(_size(path) / 1e6, 2),
        "recorded_s": round(duration, 1),
        "read_s": round(wall, 3),
        "read_msgs_per_s": round(count / wall),
        "read_x_realtime": round(duration / wall),
        "anyreader_msgs_per_s": round(count / peer),
        "read_time_ratio": round(wall / peer, 2),
        "read_peak_mb": round(peak / 1e6, 2),
    }


def bench_replay(path: Path, topic: str) -> dict[str, Any]:
    """Replay the whole topic as one move on the virtual clock, recording it."""
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)
    route = Route.from_config(
        [{"arguments": ["", "a", "b"]}], path.parent, default_bag=path.name, default_topic=topic
    )
    out = Path(tempfile.mkdtemp(prefix="bench_bag_replay_"))

    async def main() -> tuple[float, float, bool]:
        await hub.start()
        recorder = MissionRecorder(hub, out / "run").start()
        context = PerformerContext(hub=hub, clock=clock, base_dir=path.parent, recorder=recorder)
        performer = BagNavigationPerformer(context, "nav", {"move": []}, route=route)
        await performer.start()  # measures the segment (one streaming pass)
        started = time.perf_counter()
        t0 = clock.now()
        outcome = await ActionClient(hub, "move", ("r", "a", "b")).run()
        wall = time.perf_counter() - started
        mission = clock.now() - t0
        await performer.stop()
        recorder.close()
        await hub.close()
        return wall, mission, outcome.success

    try:
        wall, mission, ok = run(main(), clock)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    return {
        "replay_ok": ok,
        "replay_mission_s": round(mission, 1),
        "replay_wall_s": round(wall, 3),
        "replay_x_realtime": round(mission / wall),
    }


def _size(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*")) if path.is_dir() else path.stat().st_size


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--bags", type=Path, default=BAGS)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args()
    sources = [(args.bags / name, topic) for name, topic in SOURCES if (args.bags / name).exists()]
    sources.append((REPO / "bags" / "kitchen_nav", "/odom"))
    sources.append((REPO / "bags" / "kitchen_nav_ros1.bag", "/robot_pose"))
    rows = []
    for path, topic in sources:
        row = bench_read(path, topic)
        row.update(bench_replay(path, topic))
        rows.append(row)
    peak_rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    if args.json:
        print(json.dumps({"rows": rows, "peak_rss_mb": round(peak_rss_mb, 1)}, indent=2))
        return 0
    header = (
        f"{'bag':26} {'topic':32} {'fmt':5} {'msgs':>6} {'MB':>5} {'rec s':>6} "
        f"{'msg/s':>8} {'peer/s':>8} {'ratio':>5} {'read x':>7} {'peak MB':>7} "
        f"{'replay s':>8} {'replay x':>8}"
    )
    print(header)
    print("-" * len(header))
    for r in rows:
        print(
            f"{r['bag']:26} {r['topic']:32} {r['format']:5} {r['messages']:>6} "
            f"{r['size_mb']:>5} {r['recorded_s']:>6} {r['read_msgs_per_s']:>8} "
            f"{r['anyreader_msgs_per_s']:>8} {r['read_time_ratio']:>5} "
            f"{r['read_x_realtime']:>7} {r['read_peak_mb']:>7} {r['replay_wall_s']:>8} "
            f"{r['replay_x_realtime']:>8}"
        )
    print(f"peak RSS of the process: {peak_rss_mb:.1f} MB")
    print("peer/s: rosbags' AnyReader deserialising the same topic; ratio: our read time / its")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
