"""An actionlib client on the project's ROS 1 node (what move_base speaks).

An action ``ns`` of type ``pkg/Name`` is five topics: the client publishes
``ns/goal`` (``NameActionGoal``) and ``ns/cancel`` (``actionlib_msgs/GoalID``) and
subscribes ``ns/status`` (``GoalStatusArray``), ``ns/feedback`` and ``ns/result``.
Goals are told apart by their GoalID (``callerid-counter-stamp``, as actionlib
makes them). A goal ends when its result arrives; if the server stops sending
status for ``server_timeout`` the goal ends LOST, so a dead server never leaves a
goal waiting forever.

A LOST goal may still be alive in the server (a network split, a stalled process):
the client keeps it in :attr:`ActionClient.abandoned` and cancels it again when the
server is back (its status arrives and it listens to our cancel topic again) and
while the server still reports the goal running (status, feedback), so a returning
move_base does not resume driving for an action the caller gave up. It is forgotten
once the server reports it terminal (or RECALLING: a cancel for a goal the server
never had), or lists no such goal for ``server_timeout`` after the cancel.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.node import Node, resolve_topic
from plansys_bridge.ros1.topics import Publisher, Subscriber

__all__ = ["AbandonedGoal", "ActionClient", "ActionOutcome", "GoalHandle", "GoalStatus"]


class GoalStatus(IntEnum):
    """actionlib_msgs/GoalStatus constants."""

    PENDING = 0
    ACTIVE = 1
    PREEMPTED = 2
    SUCCEEDED = 3
    ABORTED = 4
    REJECTED = 5
    PREEMPTING = 6
    RECALLING = 7
    RECALLED = 8
    LOST = 9

    @property
    def terminal(self) -> bool:
        return self in _TERMINAL


_TERMINAL = frozenset(
    {
        GoalStatus.PREEMPTED,
        GoalStatus.SUCCEEDED,
        GoalStatus.ABORTED,
        GoalStatus.REJECTED,
        GoalStatus.RECALLED,
        GoalStatus.LOST,
    }
)


_FORGET = _TERMINAL | {GoalStatus.RECALLING}
"""Statuses of an abandoned goal after which no cancel is needed any more."""
MAX_ABANDONED = 64
"""LOST goals remembered for a cancel at most (the oldest are forgotten first)."""


@dataclass(frozen=True)
class ActionOutcome:
    """How a goal ended: its terminal status, the server's text, the result message."""

    status: GoalStatus
    text: str
    result: Any


@dataclass
class AbandonedGoal:
    """A LOST goal the server must still be told to cancel (monotonic times)."""

    cancelled: float = -float("inf")
    """When the cancel was last sent to a ready server."""
    listed: float = -float("inf")
    """When the server last listed the goal as not yet terminal."""


FeedbackCallback = Callable[[Any], None]


class GoalHandle:
    """One goal sent by an :class:`ActionClient`."""

    def __init__(
        self, client: ActionClient, goal_id: str, on_feedback: FeedbackCallback | None
    ) -> None:
        self.client = client
        self.goal_id = goal_id
        self.status = GoalStatus.PENDING
        self.text = ""
        self.feedback: Any = None
        """The latest feedback message (the action's ``NameFeedback``)."""
        self.on_feedback = on_feedback
        self.sent = time.monotonic()
        self._done: asyncio.Future[ActionOutcome] = asyncio.get_running_loop().create_future()

    @property
    def done(self) -> bool:
        return self._done.done()

    async def result(self) -> ActionOutcome:
        """Wait for the terminal status (a cancel ends as PREEMPTED or RECALLED)."""
        return await asyncio.shield(self._done)

    def cancel(self) -> None:
        """Ask the server to cancel this goal (the outcome still arrives as usual)."""
        self.client.cancel(self.goal_id)

    def _update(self, status: int, text: str) -> None:
        if self._done.done():
            return
        try:
            self.status = GoalStatus(status)
        except ValueError:
            return
        self.text = text

    def _finish(self, status: GoalStatus, text: str, result: Any) -> None:
        if self._done.done():
            return
        self.status = status
        self.text = text
        self._done.set_result(ActionOutcome(status, text, result))


class ActionClient:
    """``await ActionClient.create(node, "/move_base", "move_base_msgs/MoveBase")``."""

    def __init__(
        self, node: Node, ns: str, action_type: str, *, server_timeout: float = 5.0
    ) -> None:
        self.node = node
        self.ns = resolve_topic(ns).rstrip("/")
        pkg, _, name = action_type.replace("/action/", "/").replace("/msg/", "/").partition("/")
        if not pkg or not name or "/" in name:
            raise Ros1Error(f"not an action type: {action_type!r} (expected pkg/Name)")
        self.pkg, self.name = pkg, name
        self.goal_type = f"{pkg}/msg/{name}ActionGoal"
        self.server_timeout = server_timeout
        self.goals: dict[str, GoalHandle] = {}
        self.abandoned: dict[str, AbandonedGoal] = {}
        """Goals given up as LOST whose cancel is still wanted, by goal id."""
        self.last_status = -float("inf")
        """time.monotonic() of the last status message from the server."""
        self._counter = 0
        self._goal_pub: Publisher | None = None
        self._cancel_pub: Publisher | None = None
        self._subs: list[Subscriber] = []
        self._watch: asyncio.Task[None] | None = None
        self._was_ready = False

    @classmethod
    async def create(
        cls, node: Node, ns: str, action_type: str, *, server_timeout: float = 5.0
    ) -> ActionClient:
        client = cls(node, ns, action_type, server_timeout=server_timeout)
        await client.start()
        return client

    async def start(self) -> None:
        node, ns, p = self.node, self.ns, f"{self.pkg}/msg/{self.name}"
        self._goal_pub = await node.advertise(f"{ns}/goal", self.goal_type)
        self._cancel_pub = await node.advertise(f"{ns}/cancel", "actionlib_msgs/msg/GoalID")
        self._subs = [
            await node.subscribe(
                f"{ns}/status", "actionlib_msgs/msg/GoalStatusArray", self._on_status
            ),
            await node.subscribe(f"{ns}/feedback", f"{p}ActionFeedback", self._on_feedback),
            await node.subscribe(f"{ns}/result", f"{p}ActionResult", self._on_result),
        ]
        self._watch = asyncio.get_running_loop().create_task(
            self._watch_server(), name=f"actionlib {ns}"
        )

    async def close(self) -> None:
        if self._watch is not None:
            self._watch.cancel()
            await asyncio.gather(self._watch, return_exceptions=True)
            self._watch = None
        for sub in self._subs:
            await sub.unsubscribe()
        self._subs = []
        for pub in (self._goal_pub, self._cancel_pub):
            if pub is not None:
                await pub.unadvertise()
        self._goal_pub = self._cancel_pub = None

    @property
    def server_ready(self) -> bool:
        """A server sends status and listens to our goal and cancel topics."""
        return (
            self._goal_pub is not None
            and self._cancel_pub is not None
            and self._goal_pub.num_connections > 0
            and self._cancel_pub.num_connections > 0
            and time.monotonic() - self.last_status < self.server_timeout
        )

    async def wait_for_server(self, timeout: float = 10.0) -> bool:
        """True once :attr:`server_ready`, False after ``timeout`` seconds."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout):
                while not self.server_ready:
                    await asyncio.sleep(0.05)
        return self.server_ready

    def stamp(self) -> Any:
        now = time.time()
        sec = int(now)
        return self.node.types.new(
            "builtin_interfaces/msg/Time", sec=sec, nanosec=int((now - sec) * 1e9)
        )

    def send_goal(self, goal: Any, on_feedback: FeedbackCallback | None = None) -> GoalHandle:
        """Publish ``goal`` (the action's ``NameGoal``) with a fresh GoalID."""
        if self._goal_pub is None:
            raise Ros1Error(f"action client {self.ns} is not started")
        types = self.node.types
        self._counter += 1
        stamp = self.stamp()
        goal_id = f"{self.node.name}-{self._counter}-{stamp.sec}.{stamp.nanosec // 1_000_000:03d}"
        handle = GoalHandle(self, goal_id, on_feedback)
        self.goals[goal_id] = handle
        header = types.new("std_msgs/msg/Header", stamp=stamp)
        gid = types.new("actionlib_msgs/msg/GoalID", stamp=stamp, id=goal_id)
        self._goal_pub.publish(types.new(self.goal_type, header=header, goal_id=gid, goal=goal))
        return handle

    def cancel(self, goal_id: str) -> None:
        """Cancel one goal (``""`` with a zero stamp cancels all, as actionlib defines)."""
        if self._cancel_pub is None:
            return
        zero = self.node.types.new("builtin_interfaces/msg/Time")
        self._cancel_pub.publish(
            self.node.types.new("actionlib_msgs/msg/GoalID", stamp=zero, id=goal_id)
        )

    # ------------------------------------------------------------ server messages

    def _on_status(self, msg: Any) -> None:
        self.last_status = now = time.monotonic()
        for status in msg.status_list:
            goal_id = status.goal_id.id
            handle = self.goals.get(goal_id)
            if handle is not None:
                handle._update(status.status, status.text)
            elif goal_id in self.abandoned:
                if status.status in _FORGET:
                    del self.abandoned[goal_id]
                else:
                    self.abandoned[goal_id].listed = now
        self._recancel()

    def _recancel(self) -> None:
        """Cancel the abandoned goals again now the server is back (and again while
        it still lists one running); forget those it has not listed for
        ``server_timeout`` since the cancel (it does not hold them)."""
        ready = self.server_ready
        back, self._was_ready = ready and not self._was_ready, ready
        if not ready:
            return
        now = time.monotonic()
        for goal_id, lost in list(self.abandoned.items()):
            running = lost.listed > lost.cancelled
            if back or (running and now - lost.cancelled >= min(1.0, self.server_timeout)):
                lost.cancelled = now
                self.cancel(goal_id)
            elif now - max(lost.cancelled, lost.listed) >= self.server_timeout:
                del self.abandoned[goal_id]

    def _on_feedback(self, msg: Any) -> None:
        handle = self.goals.get(msg.status.goal_id.id)
        lost = self.abandoned.get(msg.status.goal_id.id)
        if lost is not None:  # a goal given up is being driven: say cancel again
            lost.listed = time.monotonic()
            self._recancel()
        if handle is None or handle.done:
            return
        handle._update(msg.status.status, msg.status.text)
        handle.feedback = msg.feedback
        if handle.on_feedback is not None:
            handle.on_feedback(msg.feedback)

    def _on_result(self, msg: Any) -> None:
        handle = self.goals.pop(msg.status.goal_id.id, None)
        if handle is None:
            if msg.status.status in _FORGET:
                self.abandoned.pop(msg.status.goal_id.id, None)
            return
        try:
            status = GoalStatus(msg.status.status)
        except ValueError:
            status = GoalStatus.LOST
        if not status.terminal:
            status = GoalStatus.LOST
        handle._finish(status, msg.status.text, msg.result)

    async def _watch_server(self) -> None:
        while True:
            await asyncio.sleep(min(1.0, self.server_timeout / 2))
            self._recancel()
            if not self.goals or time.monotonic() - self.last_status < self.server_timeout:
                continue
            for goal_id, handle in list(self.goals.items()):
                if time.monotonic() - handle.sent < self.server_timeout:
                    continue
                del self.goals[goal_id]
                self._abandon(goal_id)
                handle._finish(
                    GoalStatus.LOST,
                    f"action server {self.ns} sent no status for {self.server_timeout:g} s",
                    None,
                )

    def _abandon(self, goal_id: str) -> None:
        """Remember a LOST goal so a returning server is told to cancel it."""
        self.abandoned[goal_id] = AbandonedGoal()
        while len(self.abandoned) > MAX_ABANDONED:
            del self.abandoned[next(iter(self.abandoned))]
        self._was_ready = False  # the next ready server is a returning one
