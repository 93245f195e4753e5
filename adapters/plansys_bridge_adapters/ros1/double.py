"""A move_base double on the project's own ROS 1 client, for demos on a real roscore.

``python -m plansys_bridge_adapters.ros1.double [--ns /move_base] [--speed 0.5]``
serves the move_base action (``move_base_msgs/MoveBase``) the way actionlib's
SimpleActionServer does: one goal at a time (a new goal preempts the old one),
status at 5 Hz, feedback (``base_position``) at 10 Hz while the pretend base drives
straight to the goal at ``--speed`` m/s, SUCCEEDED on arrival, PREEMPTED on cancel,
ABORTED "unknown frame" for a goal not in ``--frame``. Like TIAGo it publishes
``/mobile_base_controller/odom`` (nav_msgs/Odometry) and ``/tf`` (odom -> base_footprint),
and follows ``/nav_vel`` (geometry_msgs/Twist) when no goal is active.
It needs a ROS master (``ROS_MASTER_URI`` or ``--master``); it never uses rospy.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import math
import time
from typing import Any

from plansys_bridge.ros1.actionlib import GoalStatus
from plansys_bridge.ros1.node import Node

__all__ = ["MoveBaseDouble", "main"]

log = logging.getLogger(__name__)

RATE = 10.0


class MoveBaseDouble:
    """The action server and the pretend base; ``await run()`` until cancelled."""

    def __init__(self, node: Node, ns: str = "/move_base", speed: float = 0.5, frame: str = "map"):
        self.node = node
        self.ns = ns.rstrip("/")
        self.speed = speed
        self.frame = frame
        self.x = self.y = self.yaw = 0.0
        self.twist: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.twist_until = 0.0
        self.goal: Any = None
        self.goal_id = ""
        self.status = GoalStatus.PENDING
        self.finished: list[tuple[Any, int, str]] = []
        self.seq = 0

    async def setup(self) -> None:
        n, ns = self.node, self.ns
        self.status_pub = await n.advertise(f"{ns}/status", "actionlib_msgs/msg/GoalStatusArray")
        self.feedback_pub = await n.advertise(
            f"{ns}/feedback", "move_base_msgs/msg/MoveBaseActionFeedback"
        )
        self.result_pub = await n.advertise(
            f"{ns}/result", "move_base_msgs/msg/MoveBaseActionResult"
        )
        self.odom_pub = await n.advertise("/mobile_base_controller/odom", "nav_msgs/msg/Odometry")
        self.tf_pub = await n.advertise("/tf", "tf2_msgs/msg/TFMessage")
        await n.subscribe(f"{ns}/goal", "move_base_msgs/msg/MoveBaseActionGoal", self._on_goal)
        await n.subscribe(f"{ns}/cancel", "actionlib_msgs/msg/GoalID", self._on_cancel)
        await n.subscribe("/nav_vel", "geometry_msgs/msg/Twist", self._on_twist)

    # ------------------------------------------------------------ inputs

    def _on_goal(self, msg: Any) -> None:
        if self.goal is not None:
            self._finish(GoalStatus.PREEMPTED, "preempted by a new goal")
        frame = msg.goal.target_pose.header.frame_id
        self.goal, self.goal_id = msg.goal.target_pose, msg.goal_id.id
        self.status = GoalStatus.ACTIVE
        log.info(
            "goal %s to (%.2f, %.2f) in %s",
            self.goal_id,
            self.goal.pose.position.x,
            self.goal.pose.position.y,
            frame,
        )
        if frame != self.frame:
            self._finish(GoalStatus.ABORTED, f"unknown frame {frame}")

    def _on_cancel(self, msg: Any) -> None:
        if self.goal is not None and msg.id in ("", self.goal_id):
            self._finish(GoalStatus.PREEMPTED, "cancelled by client")

    def _on_twist(self, msg: Any) -> None:
        self.twist = (msg.linear.x, msg.linear.y, msg.angular.z)
        self.twist_until = time.monotonic() + 0.5

    # ------------------------------------------------------------ outputs

    def _header(self, frame: str = "") -> Any:
        self.seq += 1
        stamp = self._stamp()
        return self.node.types.new("std_msgs/msg/Header", seq=self.seq, stamp=stamp, frame_id=frame)

    def _stamp(self) -> Any:
        now = time.time()
        return self.node.types.new(
            "builtin_interfaces/msg/Time", sec=int(now), nanosec=int((now % 1) * 1e9)
        )

    def _goal_status(self, goal_id: str, status: int, text: str) -> Any:
        t = self.node.types
        gid = t.new("actionlib_msgs/msg/GoalID", stamp=self._stamp(), id=goal_id)
        return t.new("actionlib_msgs/msg/GoalStatus", goal_id=gid, status=status, text=text)

    def _finish(self, status: GoalStatus, text: str) -> None:
        t = self.node.types
        result = t.new(
            "move_base_msgs/msg/MoveBaseActionResult",
            header=self._header(),
            status=self._goal_status(self.goal_id, status, text),
        )
        self.result_pub.publish(result)
        self.finished = [*self.finished[-9:], (self.goal_id, int(status), text)]
        log.info("goal %s %s: %s", self.goal_id, status.name, text)
        self.goal, self.status = None, status

    def _publish_status(self) -> None:
        t = self.node.types
        statuses = [self._goal_status(g, s, txt) for g, s, txt in self.finished]
        if self.goal is not None:
            statuses.append(self._goal_status(self.goal_id, GoalStatus.ACTIVE, ""))
        self.status_pub.publish(
            t.new("actionlib_msgs/msg/GoalStatusArray", header=self._header(), status_list=statuses)
        )

    def _step(self, dt: float) -> None:
        t = self.node.types
        vx = vy = wz = 0.0
        if self.goal is not None:
            target = self.goal.pose.position
            dx, dy = target.x - self.x, target.y - self.y
            dist = math.hypot(dx, dy)
            step = self.speed * dt
            if dist <= step:
                self.x, self.y = target.x, target.y
                q = self.goal.pose.orientation
                self.yaw = 2 * math.atan2(q.z, q.w)
            else:
                vx, vy = dx / dist * self.speed, dy / dist * self.speed
                self.x += vx * dt
                self.y += vy * dt
                self.yaw = math.atan2(dy, dx)
            feedback = t.new("move_base_msgs/msg/MoveBaseFeedback")
            pose = feedback.base_position
            pose.header = self._header(self.frame)
            pose.pose.position.x, pose.pose.position.y = self.x, self.y
            pose.pose.orientation.z = math.sin(self.yaw / 2)
            pose.pose.orientation.w = math.cos(self.yaw / 2)
            self.feedback_pub.publish(
                t.new(
                    "move_base_msgs/msg/MoveBaseActionFeedback",
                    header=self._header(),
                    status=self._goal_status(self.goal_id, GoalStatus.ACTIVE, ""),
                    feedback=feedback,
                )
            )
            if dist <= step:
                self._finish(GoalStatus.SUCCEEDED, "goal reached")
        elif time.monotonic() < self.twist_until:
            vx, vy, wz = self.twist
            self.x += (vx * math.cos(self.yaw) - vy * math.sin(self.yaw)) * dt
            self.y += (vx * math.sin(self.yaw) + vy * math.cos(self.yaw)) * dt
            self.yaw += wz * dt
        self._publish_odom(vx, vy, wz)

    def _publish_odom(self, vx: float, vy: float, wz: float) -> None:
        t = self.node.types
        odom = t.new(
            "nav_msgs/msg/Odometry", header=self._header("odom"), child_frame_id="base_footprint"
        )
        odom.pose.pose.position.x, odom.pose.pose.position.y = self.x, self.y
        odom.pose.pose.orientation.z = math.sin(self.yaw / 2)
        odom.pose.pose.orientation.w = math.cos(self.yaw / 2)
        odom.twist.twist.linear.x, odom.twist.twist.linear.y = vx, vy
        odom.twist.twist.angular.z = wz
        self.odom_pub.publish(odom)
        tf = t.new(
            "geometry_msgs/msg/TransformStamped",
            header=odom.header,
            child_frame_id="base_footprint",
        )
        tf.transform.translation.x, tf.transform.translation.y = self.x, self.y
        tf.transform.rotation = odom.pose.pose.orientation
        self.tf_pub.publish(t.new("tf2_msgs/msg/TFMessage", transforms=[tf]))

    async def run(self) -> None:
        await self.setup()
        tick = 0
        while True:
            await asyncio.sleep(1.0 / RATE)
            self._step(1.0 / RATE)
            tick += 1
            if tick % 2 == 0:
                self._publish_status()


async def _main(args: argparse.Namespace) -> None:
    async with Node("move_base_double", master_uri=args.master) as node:
        await node.wait_for_master(timeout=args.wait)
        print(f"move_base double at {args.ns} on {node.master_uri}", flush=True)
        await MoveBaseDouble(node, args.ns, args.speed, args.frame).run()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m plansys_bridge_adapters.ros1.double")
    parser.add_argument("--master", default=None, help="ROS master URI (default $ROS_MASTER_URI)")
    parser.add_argument("--ns", default="/move_base", help="action namespace")
    parser.add_argument("--speed", type=float, default=0.5, help="m/s")
    parser.add_argument("--frame", default="map", help="the only goal frame accepted")
    parser.add_argument("--wait", type=float, default=10.0, help="seconds to wait for the master")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(_main(args))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
