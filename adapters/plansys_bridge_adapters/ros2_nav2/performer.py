"""The ``ros2_nav2`` performer: PDDL moves as Nav2 ``NavigateToPose`` goals over DDS.

For ``(move r1 hall kitchen)`` it looks up the destination (the ``target_arg``-th
argument, the last by default) in ``locations`` and sends a
``nav2_msgs/action/NavigateToPose`` goal (pose in ``frame_id``, orientation from
``yaw``) to ``/<action_name>`` as a ROS 2 action client on Cyclone DDS. While Nav2
drives, ``distance_remaining`` becomes the action's completion (the fraction of the
largest distance seen so far). SUCCEEDED finishes the action; ABORTED fails it with
Nav2's ``error_code`` and ``error_msg``; CANCELED (by someone else) fails it too. A
halt from the executor cancels the Nav2 goal (``cancel_goal``). A Nav2 server gone
for ``lost_after`` seconds mid-goal fails the action LOST; should that server come
back still driving the goal, the client cancels it (:mod:`plansys_bridge.ros2.actions`).

A destination of the mission that ``locations`` lacks is an error when the mission
starts, naming the key. Without a Nav2 server on the domain the performer does not
bid, and says so once. Settings: :mod:`.settings`.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.entry import PerformerConfig
from plansys_bridge.ros2.actions import (
    GOAL_STATUS,
    STATUS_LOST,
    STATUS_NAMES,
    ActionClient,
    ClientGoal,
)
from plansys_bridge.ros2.node import Ros2Node

from ..nav_goals import Pose2D, check_destinations
from .settings import Nav2Settings, NavSettings, resolve

__all__ = ["Nav2Performer"]

log = logging.getLogger(__name__)

NAV_TYPE = "nav2_msgs/action/NavigateToPose"


class Nav2Performer(ActionPerformer):
    """Drives a ROS 2 robot through Nav2's NavigateToPose action (see module docs)."""

    Settings = Nav2Settings
    lost_after: float = 5.0
    """Seconds a Nav2 server may be gone mid-goal before the action fails LOST."""

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        settings: NavSettings,
        **common: Any,
    ) -> None:
        super().__init__(context, node_name, actions, **common)
        self.settings = settings
        transport_domain = getattr(context.hub.transport, "domain_id", None)
        self.domain_id = (
            settings.domain_id
            if settings.domain_id is not None
            else transport_domain
            if isinstance(transport_domain, int)
            else 0
        )
        self._node: Ros2Node | None = None
        self._client: ActionClient | None = None
        self._double: Any = None
        self._goal: ClientGoal | None = None
        self._sending: asyncio.Future[ClientGoal] | None = None
        """A goal request on its way: a cancel meanwhile still reaches its goal."""
        self._warned_absent = False

    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        """A locations file read; every destination the domain allows has a location."""
        settings = resolve(entry.settings, entry.key, context.base_dir)
        check_destinations(settings, entry.actions, context.knowledge, entry.key)
        return replace(entry, settings=settings)

    # -- lifecycle ---------------------------------------------------------------------
    async def setup(self) -> None:
        # Cyclone opens a domain once per process: share the hub's configuration.
        transport = self.context.hub.transport
        config = getattr(transport, "config", None)
        if getattr(transport, "domain_id", None) != self.domain_id or not isinstance(config, str):
            config = None
        if self.settings.double is not None:
            from .double import Nav2Double

            self._double = await Nav2Double(
                self.domain_id,
                action_name=self.settings.action_name,
                speed=self.settings.double.speed,
                blocked=[
                    (loc.x, loc.y)
                    for loc in (
                        self.settings.locations[b.strip().lower()]
                        for b in self.settings.double.blocked
                    )
                ],
                config=config,
            ).start()
        self._node = Ros2Node(self.domain_id, config=config, name=self.node_name)
        await self._node.start()
        self._client = ActionClient(
            self._node, self.settings.action_name, NAV_TYPE, server_timeout=self.lost_after
        )

    async def teardown(self) -> None:
        if self._client is not None:
            await self._client.close()
            self._client = None
        if self._node is not None:
            await self._node.close()
            self._node = None
        if self._double is not None:
            await self._double.close()
            self._double = None

    @property
    def ready(self) -> bool:
        """Whether a Nav2 action server is matched on the domain (all three services)."""
        return self._client is not None and self._client.is_ready()

    def accepts(self, goal: ActionGoal) -> bool:
        ready = self.ready
        if not ready and not self._warned_absent:
            self._warned_absent = True
            log.warning(
                "performer %s: no Nav2 action server /%s on DDS domain %d; not bidding",
                self.node_name,
                self.settings.action_name.strip("/"),
                self.domain_id,
            )
        elif ready:
            self._warned_absent = False
        return ready

    # -- execution ---------------------------------------------------------------------
    def _target(self, goal: ActionGoal) -> tuple[str, Pose2D]:
        try:
            name = goal.arguments[self.settings.target_arg].lower()
        except IndexError:
            raise ActionFailed(
                f"{goal.full_name} has no argument {self.settings.target_arg} (target_arg)"
            ) from None
        location = self.settings.locations.get(name)
        if location is None:
            raise ActionFailed(f"no location for {name!r} in this performer's locations")
        return name, location

    def _pose(self, location: Pose2D) -> Any:
        pose = dds_type("geometry_msgs/msg/PoseStamped")()
        now = time.time()
        pose.header.stamp.sec = int(now)
        pose.header.stamp.nanosec = int((now - int(now)) * 1e9)
        pose.header.frame_id = self.settings.frame_id
        pose.pose.position.x, pose.pose.position.y = location.x, location.y
        q = location.quaternion()
        o = pose.pose.orientation
        o.x, o.y, o.z, o.w = q
        return pose

    async def execute(self, goal: ActionGoal) -> str | None:
        name, location = self._target(goal)
        client = self._client
        if client is None:
            raise ActionFailed("not connected to DDS")
        action = "/" + self.settings.action_name.strip("/")
        farthest = 0.0

        def on_feedback(feedback: Any) -> None:
            nonlocal farthest
            left = max(0.0, float(feedback.distance_remaining))
            farthest = max(farthest, left)
            done = 1.0 - left / farthest if farthest > 0 else 0.0
            if self.goal is not None:
                self.feedback(done, f"{left:.2f} m to {name}")

        message = dds_type(f"{NAV_TYPE}_Goal")(pose=self._pose(location))
        # shielded: a cancel (a halt, the end of the mission, SIGTERM) arriving while
        # Nav2 accepts the goal leaves the request running, so on_cancel cancels the
        # goal it started instead of leaving the robot driving
        self._sending = asyncio.ensure_future(client.send_goal(message, on_feedback=on_feedback))
        handle = await asyncio.shield(self._sending)
        self._sending = None
        if not handle.accepted:
            raise ActionFailed(f"{action} rejected the goal to {name}")
        self._goal = handle  # kept when cancelled: on_cancel cancels it on Nav2
        status, result = await handle.result()
        self._goal = None
        if status == GOAL_STATUS["STATUS_SUCCEEDED"]:
            return f"reached {name}"
        if status == STATUS_LOST:
            raise ActionFailed(f"{action} LOST the goal to {name}: {handle.text}")
        detail = f"error_code {result.error_code}" + (
            f": {result.error_msg}" if result.error_msg else ""
        )
        raise ActionFailed(
            f"{action} {STATUS_NAMES.get(status, str(status))} the goal to {name} ({detail})"
        )

    async def on_cancel(self, goal: ActionGoal) -> None:
        handle, self._goal = self._goal, None
        sending, self._sending = self._sending, None
        if handle is None and sending is not None:
            try:
                async with asyncio.timeout(5.0):
                    handle = await sending
            except Exception as exc:
                log.warning("performer %s: the Nav2 goal request failed: %s", self.node_name, exc)
            if handle is not None and not handle.accepted:
                handle = None
        if handle is not None:
            try:
                await handle.cancel(timeout=5.0)
            except Exception as exc:
                log.warning(
                    "performer %s: cancelling the Nav2 goal failed: %s", self.node_name, exc
                )
