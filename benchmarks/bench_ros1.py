"""TCPROS throughput and latency: the project's ROS 1 client vs rospy; bridge latency.

Against a real roscore on loopback (Debian's ros-core; rospy runs with
/usr/bin/python3). For std_msgs/String (10 kB) and nav_msgs/Odometry, a publisher
process and a subscriber process of the same implementation:

* latency: ``--latency-n`` stamped messages at ``--rate`` Hz, receive time minus
  the stamp (both processes read the same clock);
* throughput: ``--burst-n`` messages as fast as the publisher can; messages per
  second and MB/s as received.

Then the bridge: a ROS 1 publisher (the project's) sends stamped Odometry at 100 Hz
to a direct ROS 1 subscriber and, through ``plansys-bridge bridge`` in its own
process, to a Cyclone DDS reader on ``rt/odom``; the difference of the two latencies
is what the bridge adds.

Run: ``python benchmarks/bench_ros1.py [--latency-n 500] [--burst-n 3000] [--json]``
"""

from __future__ import annotations

import argparse
import asyncio
import json
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from bench_support import summary

from plansys_bridge.ros1 import Node
from plansys_bridge.ros1.roscore import SYSTEM_PYTHON, Roscore, missing_ros1

HERE = Path(__file__).resolve().parent
PAD = "x" * 10240
TYPES = {"String": "std_msgs/msg/String", "Odometry": "nav_msgs/msg/Odometry"}


def make(node: Node, kind: str, i: int) -> Any:
    now = time.time()
    if kind == "String":
        return node.types.new("std_msgs/msg/String", data=f"{i} {now:.9f} {PAD}")
    msg = node.types.new("nav_msgs/msg/Odometry")
    msg.header.seq = i
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(now), int((now % 1) * 1e9)
    msg.header.frame_id = "odom"
    msg.pose.pose.position.x = float(i)
    return msg


def read(kind: str, msg: Any) -> tuple[int, float]:
    if kind == "String":
        i, stamp, _ = msg.data.split(" ", 2)
        return int(i), float(stamp)
    return int(msg.pose.pose.position.x), msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


# ---------------------------------------------------------------- the project's roles


async def ours_pub(kind: str, lat_n: int, rate: float, burst_n: int) -> None:
    async with Node("bench_pub") as node:
        pub = await node.advertise("/bench", TYPES[kind], queue_bytes=1 << 28)
        print("ready", flush=True)
        await pub.wait_for_subscribers(1, timeout=60)
        await asyncio.sleep(0.5)
        for i in range(lat_n):
            pub.publish(make(node, kind, i))
            await asyncio.sleep(1.0 / rate)
        await asyncio.sleep(0.5)
        for i in range(lat_n, lat_n + burst_n):
            pub.publish(make(node, kind, i))
            await asyncio.sleep(0)
        await asyncio.sleep(3.0)


async def ours_sub(kind: str, lat_n: int, burst_n: int) -> None:
    lat: list[float] = []
    burst: list[float] = []

    def on_msg(msg: Any) -> None:
        now = time.time()
        i, stamp = read(kind, msg)
        if i < lat_n:
            lat.append(now - stamp)
        else:
            burst.append(now)

    async with Node("bench_sub") as node:
        await node.subscribe("/bench", TYPES[kind], on_msg)
        print("ready", flush=True)
        last = 0
        for _ in range(120):
            await asyncio.sleep(1.0)
            if burst and len(burst) == last:
                break
            last = len(burst)
    span = burst[-1] - burst[0] if len(burst) > 1 else 0.0
    print(json.dumps({"latency_s": lat, "burst_received": len(burst), "burst_s": span}))


# ---------------------------------------------------------------- orchestration


def spawn(cmd: list[str], env: dict[str, str]) -> subprocess.Popen[str]:
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    line = proc.stdout.readline()
    if line.strip() != "ready":
        proc.kill()
        raise RuntimeError(f"{cmd[:3]} did not start: {line!r}")
    return proc


def pair(core: Roscore, impl: str, kind: str, args: argparse.Namespace) -> dict[str, Any]:
    env = core.env()
    if impl == "rospy":
        base = [SYSTEM_PYTHON, str(HERE / "ros1_rospy_peer.py")]
        sub_cmd = [*base, "sub", kind, str(args.latency_n), str(args.burst_n)]
        pub_cmd = [*base, "pub", kind, str(args.latency_n), str(args.rate), str(args.burst_n)]
    else:
        base = [sys.executable, str(Path(__file__).resolve())]
        sub_cmd = [*base, "--role", "sub", "--kind", kind]
        pub_cmd = [*base, "--role", "pub", "--kind", kind]
        extra = ["--latency-n", str(args.latency_n), "--burst-n", str(args.burst_n)]
        sub_cmd += extra
        pub_cmd += [*extra, "--rate", str(args.rate)]
    sub = spawn(sub_cmd, env)
    pub = spawn(pub_cmd, env)
    out, _ = sub.communicate(timeout=300)
    pub.wait(timeout=60)
    data = json.loads(out.strip().splitlines()[-1])
    size = 10240 + 30 if kind == "String" else 0
    result = summary(data["latency_s"]) if data["latency_s"] else {}
    span = data["burst_s"] or float("nan")
    result["burst_received"] = data["burst_received"]
    result["msgs_per_s"] = data["burst_received"] / span
    if size:
        result["MB_per_s"] = result["msgs_per_s"] * size / 1e6
    return result


def bridge_latency(core: Roscore, n: int) -> dict[str, Any]:
    """Odometry at 100 Hz: direct ROS 1 subscriber vs DDS reader behind the bridge."""
    from cyclonedds.core import Listener, Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from plansys_bridge.hub.dds_config import loopback_config
    from plansys_bridge.hub.dds_participant import SharedDomain
    from plansys_bridge.interfaces.dds import dds_type

    domain = 87
    cfg = Path(tempfile.mkdtemp()) / "bridge.yaml"
    cfg.write_text(
        f"ros1: {{master_uri: {core.uri}}}\nros2: {{domain_id: {domain}}}\n"
        "topics:\n  - {topic: /bench_odom, to: /odom, type: nav_msgs/msg/Odometry, from: ros1}\n"
    )
    bridge = subprocess.Popen(
        [str(Path(sys.executable).parent / "plansys-bridge"), "bridge", str(cfg)],
        env=core.env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    ros1_lat: list[float] = []
    ros2_lat: list[float] = []
    lock = threading.Lock()

    def on_dds(reader: DataReader) -> None:
        now = time.time()
        for s in reader.take(64):
            if not hasattr(s, "header"):
                continue  # an InvalidSample: the bridge's writer went away
            with lock:
                ros2_lat.append(now - (s.header.stamp.sec + s.header.stamp.nanosec * 1e-9))

    SharedDomain.acquire(domain, loopback_config(domain))
    participant = DomainParticipant(domain)
    reader = DataReader(
        participant,
        Topic(participant, "rt/odom", dds_type("nav_msgs/msg/Odometry")),
        Qos(Policy.Reliability.Reliable(0), Policy.History.KeepLast(100)),
        listener=Listener(on_data_available=on_dds),
    )

    async def main() -> None:
        async with Node("bench_bridge", master_uri=core.uri) as node:

            def on_ros1(msg: Any) -> None:
                ros1_lat.append(time.time() - read("Odometry", msg)[1])

            await node.subscribe("/bench_odom", TYPES["Odometry"], on_ros1)
            pub = await node.advertise("/bench_odom", TYPES["Odometry"])
            await pub.wait_for_subscribers(2, timeout=60)
            await asyncio.sleep(2.0)
            ros1_lat.clear()
            with lock:
                ros2_lat.clear()
            for i in range(n):
                pub.publish(make(node, "Odometry", i))
                await asyncio.sleep(0.01)
            await asyncio.sleep(1.0)

    try:
        asyncio.run(main())
    except TimeoutError:
        bridge.terminate()
        out, _ = bridge.communicate(timeout=30)
        raise RuntimeError(f"the bridge did not subscribe; it said: {out}") from None
    finally:
        bridge.terminate()
        bridge.wait(timeout=30)
        del reader
        SharedDomain.release(domain)
    direct, bridged = summary(ros1_lat), summary(ros2_lat)
    return {
        "direct_ros1": direct,
        "through_bridge_ros2": bridged,
        "added_median_us": bridged["median_us"] - direct["median_us"],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--role", choices=("pub", "sub"))
    parser.add_argument("--kind", choices=tuple(TYPES), default="String")
    parser.add_argument("--latency-n", type=int, default=500)
    parser.add_argument("--burst-n", type=int, default=3000)
    parser.add_argument("--rate", type=float, default=200.0)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--only", choices=("tcpros", "bridge"), help="run one part")
    args = parser.parse_args()
    if args.role == "pub":
        asyncio.run(ours_pub(args.kind, args.latency_n, args.rate, args.burst_n))
        return 0
    if args.role == "sub":
        asyncio.run(ours_sub(args.kind, args.latency_n, args.burst_n))
        return 0
    reason = missing_ros1()
    if reason:
        print(f"skipped: {reason}")
        return 0
    results: dict[str, Any] = {}
    with Roscore() as core:
        if args.only != "bridge":
            for kind in TYPES:
                for impl in ("ours", "rospy"):
                    results[f"{kind}/{impl}"] = pair(core, impl, kind, args)
        if args.only != "tcpros":
            results["bridge"] = bridge_latency(core, args.latency_n)
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    for kind in TYPES if args.only != "bridge" else ():
        ours, theirs = results[f"{kind}/ours"], results[f"{kind}/rospy"]
        print(f"{kind}{' (10 kB)' if kind == 'String' else ''}:")
        for name, r in (("plansys-bridge", ours), ("rospy", theirs)):
            mb = f", {r['MB_per_s']:.1f} MB/s" if "MB_per_s" in r else ""
            print(
                f"  {name:15s} latency median {r['median_us']:8.0f} us  p99 {r['p99_us']:8.0f} us"
                f"  throughput {r['msgs_per_s']:8.0f} msg/s{mb}"
            )
        print(
            f"  ratio ours/rospy: latency {ours['median_us'] / theirs['median_us']:.2f}, "
            f"throughput {ours['msgs_per_s'] / theirs['msgs_per_s']:.2f}"
        )
    b = results.get("bridge")
    if b is None:
        return 0
    print(
        f"bridge (Odometry 100 Hz): direct ROS 1 median {b['direct_ros1']['median_us']:.0f} us, "
        f"ROS 2 through the bridge {b['through_bridge_ros2']['median_us']:.0f} us "
        f"(p99 {b['through_bridge_ros2']['p99_us']:.0f}); added {b['added_median_us']:.0f} us"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
