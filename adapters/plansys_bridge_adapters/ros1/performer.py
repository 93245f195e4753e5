"""Performer kind ``ros1_move_base``: each action is a move_base goal on a ROS 1 robot.

The PlanSys2 paper's TIAGo ran move_base on ROS 1; this performer is its navigation
action performer without ros1_bridge: it sends ``move_base_msgs/MoveBaseActionGoal``
on ``<action_ns>/goal`` (the destination's pose in ``frame_id``, orientation from
its yaw) through the project's own ROS 1 client, and

* reports completion from move_base's feedback (distance left to the goal);
* finishes on SUCCEEDED; fails with move_base's status text on ABORTED, REJECTED,
  PREEMPTED (or RECALLED / LOST);
* cancels the goal (``<action_ns>/cancel``) when the executor halts the action;
* fails LOST when move_base sends no status for 5 s mid-goal, and cancels that goal
  should move_base come back still driving it (:mod:`plansys_bridge.ros1.actionlib`);
* is NOT_READY, and does not bid, while the master does not answer or no move_base
  server listens; the node logs an unreachable master once, not per retry.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

from plansys_bridge.hub.messages import PerformerState
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.entry import PerformerConfig
from plansys_bridge.ros1.actionlib import ActionClient, GoalHandle, GoalStatus
from plansys_bridge.ros1.node import Node

from .settings import MoveBaseEntry, MoveBaseSettings, Pose2D, check_destinations, resolve

__all__ = ["MoveBasePerformer"]

log = logging.getLogger(__name__)


class MoveBasePerformer(ActionPerformer):
    """Drives move_base through actionlib; one goal per action."""

    Settings = MoveBaseEntry
    ready_period = 0.5
    """Seconds between two checks of the master and the action server."""
    server_grace = 5.0
    """Seconds without a move_base server (master up) before saying so in the log."""

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        settings: MoveBaseSettings,
        *,
        heartbeat_period: float = 1.0,
        commit_timeout: float = 2.0,
    ) -> None:
        super().__init__(
            context,
            node_name,
            actions,
            heartbeat_period=heartbeat_period,
            commit_timeout=commit_timeout,
        )
        self.settings = settings
        self.node: Node | None = None
        self.client: ActionClient | None = None
        self.handle: GoalHandle | None = None
        self._watch: asyncio.Task[None] | None = None
        self._unready_since: float | None = None
        self._said = False

    # ------------------------------------------------------------ lifecycle

    async def setup(self) -> None:
        self.node = Node(f"plansys_{self.node_name}", master_uri=self.settings.master_uri)
        await self.node.start()
        self.client = await ActionClient.create(
            self.node, self.settings.action_ns, "move_base_msgs/MoveBase"
        )

    async def start(self) -> None:
        await super().start()
        self._update_state()
        self._watch = asyncio.get_running_loop().create_task(
            self._watch_ready(), name=f"{self.node_name} ready"
        )

    async def teardown(self) -> None:
        if self._watch is not None:
            self._watch.cancel()
            await asyncio.gather(self._watch, return_exceptions=True)
            self._watch = None
        if self.client is not None:
            await self.client.close()
            self.client = None
        if self.node is not None:
            await self.node.close()
            self.node = None

    @property
    def ready(self) -> bool:
        """The master answers and a move_base server listens to our goals."""
        return bool(self.node and self.node.master_ok and self.client and self.client.server_ready)

    def accepts(self, goal: ActionGoal) -> bool:
        return self.ready

    async def _watch_ready(self) -> None:
        while True:
            await asyncio.sleep(self.ready_period)
            self._update_state()

    def _update_state(self) -> None:
        if not self.running or self.busy:
            return
        ready = self.ready
        node = self.node
        if ready or node is None or not node.master_ok:
            self._unready_since = None
        elif self._unready_since is None:
            self._unready_since = time.monotonic()
        elif time.monotonic() - self._unready_since > self.server_grace and not self._said:
            # The master's own trouble is logged once by the node; this is the other case.
            log.warning(
                "performer %s: no move_base action server at %s (master %s); not bidding",
                self.node_name,
                self.settings.action_ns,
                self.settings.master_uri,
            )
            self._said = True
        if ready:
            self._said = False
        state = PerformerState.READY if ready else PerformerState.NOT_READY
        if state != self.state:
            self.state = state
            self._publish_status()

    # ------------------------------------------------------------ actions

    def destination(self, goal: ActionGoal) -> tuple[str, Pose2D]:
        try:
            name = goal.arguments[self.settings.target_arg]
        except IndexError:
            raise ActionFailed(
                f"{goal.full_name} has no argument {self.settings.target_arg} (target_arg)"
            ) from None
        pose = self.settings.locations.get(name.lower())
        if pose is None:
            raise ActionFailed(f"no location for {name!r} in the performer's locations")
        return name, pose

    def make_goal(self, pose: Pose2D) -> Any:
        assert self.node is not None
        types = self.node.types
        goal = types.new("move_base_msgs/msg/MoveBaseGoal")
        target = goal.target_pose
        target.header.frame_id = self.settings.frame_id
        target.header.stamp = self.client.stamp() if self.client else target.header.stamp
        target.pose.position.x, target.pose.position.y = pose.x, pose.y
        q = target.pose.orientation
        q.x, q.y, q.z, q.w = pose.quaternion()
        return goal

    async def execute(self, goal: ActionGoal) -> str | None:
        name, pose = self.destination(goal)
        client = self.client
        if client is None or not self.ready:
            raise ActionFailed(f"move_base at {self.settings.action_ns} is not reachable")
        start: list[float] = []

        def on_feedback(feedback: Any) -> None:
            position = feedback.base_position.pose.position
            left = math.hypot(pose.x - position.x, pose.y - position.y)
            if not start:
                start.append(max(left, 1e-6))
            completion = 1.0 - min(1.0, left / start[0])
            with contextlib.suppress(Exception):
                self.feedback(completion, f"{left:.2f} m to {name}")

        self.handle = client.send_goal(self.make_goal(pose), on_feedback)
        try:
            outcome = await self.handle.result()
        finally:
            if self.handle is not None and self.handle.done:
                self.handle = None
        if outcome.status is GoalStatus.SUCCEEDED:
            return f"reached {name}" + (f": {outcome.text}" if outcome.text else "")
        text = outcome.text or "no reason given"
        raise ActionFailed(f"move_base {outcome.status.name} going to {name}: {text}")

    async def on_cancel(self, goal: ActionGoal) -> None:
        handle, self.handle = self.handle, None
        if handle is None or handle.done:
            return
        handle.cancel()
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(2.0):
                await handle.result()

    # ------------------------------------------------------------ config

    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        """The master and namespace checked; every destination has a location."""
        settings = resolve(entry.settings, entry.key)
        check_destinations(settings, entry.actions, context.knowledge, entry.key)
        return replace(entry, settings=settings)
