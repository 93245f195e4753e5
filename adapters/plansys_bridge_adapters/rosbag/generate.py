"""Generate the project's small demo bags: a robot driving between rooms of a flat.

``python -m plansys_bridge_adapters.rosbag.generate bags/`` writes:

* ``kitchen_nav/`` — a ROS 2 bag (MCAP): ``/odom`` (nav_msgs/Odometry, 10 Hz) and
  ``/amcl_pose`` (geometry_msgs/PoseWithCovarianceStamped, 2 Hz) of five moves of
  10-15 s each, like the TIAGo moves of the PlanSys2 paper, separated by short stops;
* ``kitchen_nav_ros1.bag`` — the same drive as a ROS 1 bag (``/robot_pose``,
  geometry_msgs/PoseStamped, 10 Hz), to exercise the ROS 1 -> ROS 2 conversion;
* ``kitchen_nav.segments.yaml`` — which time window of the bags serves which move,
  in the ``segments`` format of the bag navigation performer.

The output is deterministic (fixed start time, no randomness), so regenerating the
files gives the same trajectories. The robot follows a polyline through doorways
with a smooth (cosine) speed profile and heads along its direction of travel.
"""

from __future__ import annotations

import argparse
import itertools
import math
import shutil
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

ROOMS: dict[str, tuple[float, float]] = {
    "kitchen": (0.0, 0.0),
    "livingroom": (6.0, 0.5),
    "bedroom": (6.5, 6.0),
    "bathroom": (1.0, 6.5),
}
"""Room centres in the map frame (metres)."""

DOORS: dict[frozenset[str], list[tuple[float, float]]] = {
    frozenset({"kitchen", "livingroom"}): [(3.0, -0.5)],
    frozenset({"livingroom", "bedroom"}): [(6.8, 3.0)],
    frozenset({"bedroom", "bathroom"}): [(4.0, 6.8), (3.0, 6.8)],
    frozenset({"bathroom", "kitchen"}): [(0.3, 3.2)],
    frozenset({"kitchen", "bedroom"}): [(3.0, -0.5), (6.8, 3.0)],
}


@dataclass(frozen=True)
class Move:
    origin: str
    target: str
    duration: float


MOVES: tuple[Move, ...] = (
    Move("kitchen", "livingroom", 12.0),
    Move("livingroom", "bedroom", 14.0),
    Move("bedroom", "bathroom", 11.0),
    Move("bathroom", "kitchen", 13.0),
    Move("kitchen", "bedroom", 15.0),
)

START_NS = 1_700_000_000_000_000_000
"""Bag start time (2023-11-14T22:13:20Z); fixed so outputs are reproducible."""
PAUSE = 1.5  # seconds standing still before each move and at the end
ODOM_HZ = 10.0
AMCL_HZ = 2.0


def waypoints(move: Move) -> list[tuple[float, float]]:
    doors = DOORS[frozenset({move.origin, move.target})]
    a, b = ROOMS[move.origin], ROOMS[move.target]
    # Door lists are written from the first room named in insertion order.
    if math.dist(a, doors[0]) > math.dist(b, doors[0]):
        doors = list(reversed(doors))
    return [a, *doors, b]


def point_along(points: Sequence[tuple[float, float]], s: float) -> tuple[float, float, float]:
    """Position and heading at arc length ``s`` along a polyline."""
    for (x0, y0), (x1, y1) in itertools.pairwise(points):
        seg = math.dist((x0, y0), (x1, y1))
        heading = math.atan2(y1 - y0, x1 - x0)
        if s <= seg or (x1, y1) == points[-1]:
            f = min(1.0, s / seg) if seg > 0 else 1.0
            return x0 + f * (x1 - x0), y0 + f * (y1 - y0), heading
        s -= seg
    x, y = points[-1]
    return x, y, 0.0


@dataclass(frozen=True)
class State:
    t: float
    x: float
    y: float
    yaw: float
    v: float
    w: float


def trajectory(rate: float) -> tuple[list[tuple[Move, float, float]], Iterator[State]]:
    """The schedule ``[(move, start s, end s)]`` and a generator of states at ``rate``."""
    schedule: list[tuple[Move, float, float]] = []
    t = PAUSE
    for move in MOVES:
        schedule.append((move, t, t + move.duration))
        t += move.duration + PAUSE
    total = t

    def states() -> Iterator[State]:
        dt = 1.0 / rate
        yaw = 0.0
        x, y = ROOMS[MOVES[0].origin]
        prev_yaw = yaw
        for i in range(round(total * rate) + 1):
            now = i * dt
            v = 0.0
            for move, start, end in schedule:
                if start <= now <= end:
                    pts = waypoints(move)
                    length = sum(math.dist(p, q) for p, q in itertools.pairwise(pts))
                    phase = (now - start) / move.duration
                    s = length * (1.0 - math.cos(math.pi * phase)) / 2.0
                    x, y, yaw = point_along(pts, s)
                    v = length * math.pi * math.sin(math.pi * phase) / (2.0 * move.duration)
                    break
            turn = math.atan2(math.sin(yaw - prev_yaw), math.cos(yaw - prev_yaw))
            w = turn / dt if i else 0.0
            prev_yaw = yaw
            yield State(now, x, y, yaw, v, w)

    return schedule, states()


def _quat(ts: Typestore, yaw: float) -> Any:
    q = ts.types["geometry_msgs/msg/Quaternion"]
    return q(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def _pose(ts: Typestore, s: State) -> Any:
    t = ts.types
    return t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=s.x, y=s.y, z=0.0), orientation=_quat(ts, s.yaw)
    )


def _header(ts: Typestore, s: State, frame: str, ros1: bool = False) -> Any:
    t = ts.types
    ns = START_NS + round(s.t * 1e9)
    stamp = t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
    if ros1:
        return t["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
    return t["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)


def _cov(diag: float) -> np.ndarray:
    cov = np.zeros(36, dtype=np.float64)
    cov[[0, 7, 35]] = diag
    return cov


def write_ros2(out: Path) -> Path:
    ts = get_typestore(Stores.ROS2_HUMBLE)
    t = ts.types
    path = out / "kitchen_nav"
    if path.exists():
        shutil.rmtree(path)
    with Writer2(path, version=Writer2.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP) as w:
        odom = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        amcl = w.add_connection(
            "/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped", typestore=ts
        )
        _, states = trajectory(ODOM_HZ)
        every = round(ODOM_HZ / AMCL_HZ)
        for i, s in enumerate(states):
            ns = START_NS + round(s.t * 1e9)
            twist = t["geometry_msgs/msg/Twist"](
                linear=t["geometry_msgs/msg/Vector3"](x=s.v, y=0.0, z=0.0),
                angular=t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=s.w),
            )
            msg = t["nav_msgs/msg/Odometry"](
                header=_header(ts, s, "odom"),
                child_frame_id="base_footprint",
                pose=t["geometry_msgs/msg/PoseWithCovariance"](
                    pose=_pose(ts, s), covariance=_cov(0.01)
                ),
                twist=t["geometry_msgs/msg/TwistWithCovariance"](
                    twist=twist, covariance=_cov(0.01)
                ),
            )
            w.write(odom, ns, ts.serialize_cdr(msg, "nav_msgs/msg/Odometry"))
            if i % every == 0:
                pose = t["geometry_msgs/msg/PoseWithCovarianceStamped"](
                    header=_header(ts, s, "map"),
                    pose=t["geometry_msgs/msg/PoseWithCovariance"](
                        pose=_pose(ts, s), covariance=_cov(0.05)
                    ),
                )
                w.write(
                    amcl, ns, ts.serialize_cdr(pose, "geometry_msgs/msg/PoseWithCovarianceStamped")
                )
    return path


def write_ros1(out: Path) -> Path:
    ts = get_typestore(Stores.ROS1_NOETIC)
    path = out / "kitchen_nav_ros1.bag"
    path.unlink(missing_ok=True)
    with Writer1(path) as w:
        conn = w.add_connection("/robot_pose", "geometry_msgs/msg/PoseStamped", typestore=ts)
        _, states = trajectory(ODOM_HZ)
        for s in states:
            msg = ts.types["geometry_msgs/msg/PoseStamped"](
                header=_header(ts, s, "map", ros1=True), pose=_pose(ts, s)
            )
            w.write(
                conn,
                START_NS + round(s.t * 1e9),
                ts.serialize_ros1(msg, "geometry_msgs/msg/PoseStamped"),
            )
    return path


def segments_table() -> list[dict[str, object]]:
    """The ``segments`` config of the performer for the generated ROS 2 bag."""
    schedule, _ = trajectory(ODOM_HZ)
    return [
        {
            "name": f"{m.origin}->{m.target}",
            "arguments": ["", m.origin, m.target],
            "start": round(start, 3),
            "end": round(end, 3),
        }
        for m, start, end in schedule
    ]


def write_segments(out: Path) -> Path:
    path = out / "kitchen_nav.segments.yaml"
    header = (
        "# Generated by `python -m plansys_bridge_adapters.rosbag.generate`.\n"
        "# Which time window (seconds after the bag's first message) of kitchen_nav/\n"
        "# and kitchen_nav_ros1.bag serves which move: arguments are (robot from to).\n"
    )
    path.write_text(header + yaml.safe_dump(segments_table(), sort_keys=False))
    return path


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("out", type=Path, help="folder to write the bags into (e.g. bags/)")
    args = parser.parse_args(argv)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    for path in (write_ros2(out), write_ros1(out), write_segments(out)):
        size = (
            sum(f.stat().st_size for f in path.rglob("*")) if path.is_dir() else path.stat().st_size
        )
        print(f"wrote {path} ({size / 1024:.0f} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
