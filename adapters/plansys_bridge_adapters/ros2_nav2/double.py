"""A Nav2 ``NavigateToPose`` action server double on DDS, for tests and demos.

It stands in for Nav2's bt_navigator: it serves ``nav2_msgs/action/NavigateToPose``
under ROS 2's names (``/navigate_to_pose/_action/send_goal`` and the rest, see
:mod:`plansys_bridge.ros2.actions`), drives a point robot in a straight line towards
each goal at ``speed`` m/s, turns to the goal's heading on arrival, and sends feedback
at ``rate`` Hz with ``current_pose``, ``distance_remaining``, ``navigation_time`` and
``estimated_time_remaining`` as Nav2 does. A cancel stops the robot where it is and
ends the goal CANCELED. Goals within 0.5 m of a point in ``blocked`` end ABORTED
with Nav2's NO_VALID_PATH code, as a planner that finds no path would.

Standalone::

    python -m plansys_bridge_adapters.ros2_nav2.double --domain-id 42 --speed 1.0
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import math
from collections.abc import Iterable
from typing import Any

from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.ros2.actions import GOAL_STATUS, ActionServer, ServerGoal
from plansys_bridge.ros2.node import Ros2Node

__all__ = ["NO_VALID_PATH", "Nav2Double", "main"]

log = logging.getLogger(__name__)

NAV_TYPE = "nav2_msgs/action/NavigateToPose"
NO_VALID_PATH = 204
"""Nav2's ComputePathToPose NO_VALID_PATH, the code bt_navigator reports for a blocked goal."""


def _duration(seconds: float) -> Any:
    sec = int(seconds)
    return dds_type("builtin_interfaces/msg/Duration")(sec=sec, nanosec=int((seconds - sec) * 1e9))


class Nav2Double:
    """The action server double; ``start()`` on a running loop, ``close()`` when done."""

    def __init__(
        self,
        domain_id: int,
        *,
        action_name: str = "navigate_to_pose",
        speed: float = 1.0,
        rate: float = 10.0,
        start: tuple[float, float] = (0.0, 0.0),
        blocked: Iterable[tuple[float, float]] = (),
        config: str | None = None,
    ) -> None:
        self.node = Ros2Node(domain_id, config=config, name="nav2_double")
        self.action_name = action_name
        self.speed = float(speed)
        self.period = 1.0 / float(rate)
        self.x, self.y = start
        self.yaw = 0.0
        self.blocked = [tuple(b) for b in blocked]
        self.goals: list[tuple[float, float]] = []
        """Every goal position received, in order."""
        self._server: ActionServer | None = None

    async def start(self) -> Nav2Double:
        await self.node.start()
        self._server = ActionServer(self.node, self.action_name, NAV_TYPE, self._navigate)
        return self

    async def close(self) -> None:
        if self._server is not None:
            await self._server.close()
            self._server = None
        await self.node.close()

    async def _navigate(self, handle: ServerGoal) -> tuple[int, Any]:
        result = dds_type(f"{NAV_TYPE}_Result")
        pose = handle.goal.pose
        gx, gy = float(pose.pose.position.x), float(pose.pose.position.y)
        self.goals.append((gx, gy))
        if any(math.hypot(gx - bx, gy - by) < 0.5 for bx, by in self.blocked):
            await asyncio.sleep(self.period)
            return GOAL_STATUS["STATUS_ABORTED"], result(
                error_code=NO_VALID_PATH, error_msg=f"no valid path to ({gx:g}, {gy:g})"
            )
        feedback = dds_type(f"{NAV_TYPE}_Feedback")
        loop = asyncio.get_running_loop()
        started = loop.time()
        while True:
            remaining = math.hypot(gx - self.x, gy - self.y)
            current = dds_type("geometry_msgs/msg/PoseStamped")(header=pose.header)
            current.pose.position.x, current.pose.position.y = self.x, self.y
            handle.publish_feedback(
                feedback(
                    current_pose=current,
                    navigation_time=_duration(loop.time() - started),
                    estimated_time_remaining=_duration(remaining / self.speed),
                    distance_remaining=remaining,
                )
            )
            if handle.cancel_requested.is_set():
                return GOAL_STATUS["STATUS_CANCELED"], result()
            if remaining < 1e-6:
                q = pose.pose.orientation
                self.yaw = 2.0 * math.atan2(float(q.z), float(q.w))
                return GOAL_STATUS["STATUS_SUCCEEDED"], result()
            step = min(remaining, self.speed * self.period)
            self.x += (gx - self.x) / remaining * step
            self.y += (gy - self.y) / remaining * step
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(handle.cancel_requested.wait(), self.period)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--domain-id", type=int, default=0)
    parser.add_argument("--action-name", default="navigate_to_pose")
    parser.add_argument("--speed", type=float, default=1.0, help="m/s")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")

    async def serve() -> None:
        double = await Nav2Double(
            args.domain_id, action_name=args.action_name, speed=args.speed
        ).start()
        log.info("Nav2 double: /%s on DDS domain %d", args.action_name, args.domain_id)
        try:
            await asyncio.Event().wait()
        finally:
            await double.close()

    try:
        asyncio.run(serve())
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
