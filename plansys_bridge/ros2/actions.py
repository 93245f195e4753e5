"""ROS 2 actions over Cyclone DDS: three services and two topics, as rcl_action lays them out.

For an action ``/navigate_to_pose`` of type ``nav2_msgs/action/NavigateToPose``
(ros2/rcl, ``rcl_action/src/rcl_action/names.c`` and ``action_client.c`` /
``action_server.c``, branch rolling):

* ``<name>/_action/send_goal`` service, type ``..._SendGoal`` (request ``goal_id``
  UUID + ``goal``; response ``accepted`` + ``stamp``);
* ``<name>/_action/get_result`` service, type ``..._GetResult`` (request ``goal_id``;
  response ``status`` + ``result``, answered once the goal is terminal);
* ``<name>/_action/cancel_goal`` service, type ``action_msgs/srv/CancelGoal``;
* ``<name>/_action/feedback`` topic, ``..._FeedbackMessage`` (``goal_id`` + ``feedback``),
  QoS ``rmw_qos_profile_default``;
* ``<name>/_action/status`` topic, ``action_msgs/msg/GoalStatusArray``, QoS
  ``rcl_action_qos_profile_status_default`` (reliable, transient-local, keep last 1).

Services use :mod:`plansys_bridge.ros2.services` (``rq/``/``rr/`` with the request
header); topics are ``rt/<name>``. Goal ids are ``unique_identifier_msgs/UUID``
(16 random bytes). Cancel requests follow ``rcl_action_process_cancel_request``: a
zero goal id and zero stamp cancel every goal, a zero id with a stamp every goal
accepted at or before it, an id that goal (plus, with a stamp, the earlier ones).

rcl_action's client waits for a result forever; this one ends a goal
:data:`STATUS_LOST` when the server's services stay unmatched for ``server_timeout``
(the server process died or dropped off the network), so the caller can give up.
Such a goal may still be running in a server that returns, so the client keeps it
in :attr:`ActionClient.abandoned` and sends ``cancel_goal`` for it whenever the
server is back, until the server reports it terminal (status topic, or a cancel
answered ERROR_GOAL_TERMINATED / ERROR_UNKNOWN_GOAL_ID).
"""

from __future__ import annotations

import asyncio
import logging
import time
import uuid
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.errors import HubError
from plansys_bridge.interfaces.dds import dds_type, ros2_constants
from plansys_bridge.ros2.node import ACTION_STATUS_QOS, DEFAULT_QOS, Ros2Node
from plansys_bridge.ros2.services import ServiceClient, ServiceServer

__all__ = [
    "GOAL_STATUS",
    "STATUS_LOST",
    "ActionClient",
    "ActionServer",
    "ClientGoal",
    "ServerGoal",
    "action_names",
]

log = logging.getLogger(__name__)

GOAL_STATUS: dict[str, int] = ros2_constants("action_msgs/msg/GoalStatus")
"""STATUS_UNKNOWN 0, ACCEPTED 1, EXECUTING 2, CANCELING 3, SUCCEEDED 4, CANCELED 5, ABORTED 6."""
_S = GOAL_STATUS
_TERMINAL = {_S["STATUS_SUCCEEDED"], _S["STATUS_CANCELED"], _S["STATUS_ABORTED"]}
_CANCEL = ros2_constants("action_msgs/srv/CancelGoal_Response")
KEEP_TERMINAL = 64
"""How many ended goals an action server keeps for get_result and the status topic."""
STATUS_LOST = -1
"""Not a ROS 2 status: the client gave the goal up because its server went away."""
STATUS_NAMES = {v: k.removeprefix("STATUS_") for k, v in _S.items()} | {STATUS_LOST: "LOST"}
MAX_ABANDONED = 64
"""LOST goals remembered for a cancel at most (the oldest are forgotten first)."""


def action_names(action: str) -> dict[str, str]:
    """The service and topic names of ``action`` (rcl_action's names.c)."""
    base = "/" + action.strip("/")
    if base == "/":
        raise HubError(f"invalid action name {action!r}")
    return {
        part: f"{base}/_action/{part}"
        for part in ("send_goal", "get_result", "cancel_goal", "feedback", "status")
    }


def _stamp(seconds: float | None = None) -> Any:
    now = time.time() if seconds is None else seconds
    sec = int(now)
    return dds_type("builtin_interfaces/msg/Time")(sec=sec, nanosec=int((now - sec) * 1e9))


def _seconds(stamp: Any) -> float:
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def _uuid(goal_id: bytes) -> Any:
    return dds_type("unique_identifier_msgs/msg/UUID")(uuid=list(goal_id))


def _goal_id(msg: Any) -> bytes:
    return bytes(msg.uuid)


# ====================================================================== server


@dataclass
class ServerGoal:
    """One goal on the server: its message, state, and a way to send feedback."""

    goal_id: bytes
    goal: Any
    accepted_at: float
    server: ActionServer
    status: int = _S["STATUS_ACCEPTED"]
    result: Any = None
    cancel_requested: asyncio.Event = field(default_factory=asyncio.Event)
    done: asyncio.Event = field(default_factory=asyncio.Event)

    def publish_feedback(self, feedback: Any) -> None:
        self.server.publish_feedback(self, feedback)


Execute = Callable[[ServerGoal], Awaitable[tuple[int, Any]]]
"""Runs a goal; returns (terminal status, result message). Should watch cancel_requested."""
Accept = Callable[[Any], bool]


class ActionServer:
    """Serves a ROS 2 action on a started node.

    ``accept(goal)`` decides on each goal (default: accept); accepted goals run
    ``execute(handle)`` as tasks, which return the terminal status (SUCCEEDED,
    ABORTED or CANCELED) and the result message. A cancel request marks the goal
    CANCELING and sets ``handle.cancel_requested``; ``execute`` decides when it has
    stopped. Terminal goals keep their result until the server closes, so a late
    ``get_result`` still gets it.
    """

    def __init__(
        self,
        node: Ros2Node,
        action: str,
        action_type: str,
        execute: Execute,
        *,
        accept: Accept | None = None,
    ) -> None:
        self.node = node
        self.action_type = action_type
        self.names = action_names(action)
        self._execute = execute
        self._accept = accept or (lambda _goal: True)
        self._result_type = dds_type(f"{action_type}_Result")
        self._feedback_type = dds_type(f"{action_type}_FeedbackMessage")
        self._status_array = dds_type("action_msgs/msg/GoalStatusArray")
        self.goals: dict[bytes, ServerGoal] = {}
        self._tasks: set[asyncio.Task[None]] = set()
        self._services = [
            ServiceServer(node, self.names["send_goal"], f"{action_type}_SendGoal", self._send),
            ServiceServer(
                node, self.names["get_result"], f"{action_type}_GetResult", self._get_result
            ),
            ServiceServer(
                node, self.names["cancel_goal"], "action_msgs/srv/CancelGoal", self._cancel
            ),
        ]
        self._feedback = node.writer(
            "rt" + self.names["feedback"], self._feedback_type, DEFAULT_QOS
        )
        self._status = node.writer(
            "rt" + self.names["status"], self._status_array, ACTION_STATUS_QOS
        )

    # -- services ----------------------------------------------------------------------
    def _send(self, request: Any) -> Any:
        response = dds_type(f"{self.action_type}_SendGoal_Response")
        goal_id = _goal_id(request.goal_id)
        if goal_id in self.goals or not self._accept(request.goal):
            return response(accepted=False, stamp=_stamp())
        now = time.time()
        handle = ServerGoal(goal_id, request.goal, now, self)
        self.goals[goal_id] = handle
        task = self.node.loop.create_task(self._run(handle))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        self._publish_status()
        return response(accepted=True, stamp=_stamp(now))

    async def _run(self, handle: ServerGoal) -> None:
        handle.status = (
            _S["STATUS_EXECUTING"]
            if not handle.cancel_requested.is_set()
            else (_S["STATUS_CANCELING"])
        )
        self._publish_status()
        try:
            status, result = await self._execute(handle)
        except asyncio.CancelledError:
            status, result = _S["STATUS_ABORTED"], self._result_type()
            self._finish(handle, status, result)
            raise
        except Exception as exc:
            log.error("action %s: goal %s failed: %s", self.names["send_goal"], handle, exc)
            status, result = _S["STATUS_ABORTED"], self._result_type()
        if status not in _TERMINAL:
            status = _S["STATUS_ABORTED"]
        self._finish(handle, status, result)

    def _finish(self, handle: ServerGoal, status: int, result: Any) -> None:
        handle.status, handle.result = status, result
        handle.done.set()
        # Terminal goals stay listed (and their results available) until more than
        # KEEP_TERMINAL have ended, oldest first: rcl_action expires them by age
        # (result_timeout); a bound keeps every status message small.
        ended = [g for g in self.goals.values() if g.status in _TERMINAL]
        for old in ended[: max(0, len(ended) - KEEP_TERMINAL)]:
            del self.goals[old.goal_id]
        self._publish_status()

    async def _get_result(self, request: Any) -> Any:
        response = dds_type(f"{self.action_type}_GetResult_Response")
        handle = self.goals.get(_goal_id(request.goal_id))
        if handle is None:
            return response(status=_S["STATUS_UNKNOWN"])
        await handle.done.wait()
        return response(status=handle.status, result=handle.result)

    def _cancel(self, request: Any) -> Any:
        response = dds_type("action_msgs/srv/CancelGoal_Response")
        goal_id = _goal_id(request.goal_info.goal_id)
        before = _seconds(request.goal_info.stamp)
        cancel_all = not any(goal_id) and before == 0.0
        chosen = [
            h
            for h in self.goals.values()
            if cancel_all or h.goal_id == goal_id or (before and h.accepted_at <= before)
        ]
        if any(goal_id) and goal_id not in self.goals and not before:
            return response(return_code=_CANCEL["ERROR_UNKNOWN_GOAL_ID"])
        live = [h for h in chosen if h.status not in _TERMINAL]
        if chosen and not live:
            return response(return_code=_CANCEL["ERROR_GOAL_TERMINATED"])
        if not live:
            return response(return_code=_CANCEL["ERROR_REJECTED"])
        info = dds_type("action_msgs/msg/GoalInfo")
        for h in live:
            h.status = _S["STATUS_CANCELING"]
            h.cancel_requested.set()
        self._publish_status()
        return response(
            return_code=_CANCEL["ERROR_NONE"],
            goals_canceling=[
                info(goal_id=_uuid(h.goal_id), stamp=_stamp(h.accepted_at)) for h in live
            ],
        )

    # -- topics ------------------------------------------------------------------------
    def publish_feedback(self, handle: ServerGoal, feedback: Any) -> None:
        self._feedback.write(self._feedback_type(goal_id=_uuid(handle.goal_id), feedback=feedback))

    def _publish_status(self) -> None:
        status = dds_type("action_msgs/msg/GoalStatus")
        info = dds_type("action_msgs/msg/GoalInfo")
        self._status.write(
            self._status_array(
                status_list=[
                    status(
                        goal_info=info(goal_id=_uuid(h.goal_id), stamp=_stamp(h.accepted_at)),
                        status=h.status,
                    )
                    for h in self.goals.values()
                ]
            )
        )

    async def close(self) -> None:
        await cancel_and_wait(*self._tasks)
        for service in self._services:
            await service.close()
        self.node.remove(self._feedback, self._status)


# ====================================================================== client


@dataclass
class ClientGoal:
    """A goal sent by :class:`ActionClient`: accepted or not, its status and result."""

    goal_id: bytes
    accepted: bool
    client: ActionClient
    status: int = _S["STATUS_UNKNOWN"]
    on_feedback: Callable[[Any], None] | None = None
    text: str = ""
    """Why a LOST goal was given up."""
    lost: asyncio.Event = field(default_factory=asyncio.Event)

    async def result(self, timeout: float | None = None) -> tuple[int, Any]:
        """Wait for the terminal status and the result (get_result service)."""
        return await self.client.get_result(self, timeout=timeout)

    async def cancel(self, timeout: float = 10.0) -> Any:
        """Ask the server to cancel this goal; returns the CancelGoal response."""
        return await self.client.cancel(self, timeout=timeout)


class ActionClient:
    """Sends goals to a ROS 2 action server, follows feedback and status."""

    def __init__(
        self, node: Ros2Node, action: str, action_type: str, *, server_timeout: float = 5.0
    ) -> None:
        self.node = node
        self.server_timeout = server_timeout
        """Seconds the server may stay unmatched before its running goals end LOST."""
        self.abandoned: dict[bytes, bool] = {}
        """Goals given up as LOST whose cancel is still wanted: goal id -> whether the
        server, while up, answered it (it is asked again if it goes and comes back)."""
        self._watch: asyncio.Task[None] | None = None
        self._result_type = dds_type(f"{action_type}_Result")
        self.action_type = action_type
        self.names = action_names(action)
        self._send = ServiceClient(node, self.names["send_goal"], f"{action_type}_SendGoal")
        self._result = ServiceClient(node, self.names["get_result"], f"{action_type}_GetResult")
        self._cancel = ServiceClient(node, self.names["cancel_goal"], "action_msgs/srv/CancelGoal")
        self._goals: dict[bytes, ClientGoal] = {}
        self._feedback = node.reader(
            "rt" + self.names["feedback"],
            dds_type(f"{action_type}_FeedbackMessage"),
            DEFAULT_QOS,
            self._on_feedback,
        )
        self._status = node.reader(
            "rt" + self.names["status"],
            dds_type("action_msgs/msg/GoalStatusArray"),
            ACTION_STATUS_QOS,
            self._on_status,
        )

    def is_ready(self) -> bool:
        return all(c.is_ready() for c in (self._send, self._result, self._cancel))

    async def wait_for_server(self, timeout: float = 10.0) -> None:
        for client in (self._send, self._result, self._cancel):
            await client.wait_for_service(timeout)

    async def send_goal(
        self,
        goal: Any,
        *,
        on_feedback: Callable[[Any], None] | None = None,
        timeout: float = 10.0,
    ) -> ClientGoal:
        """Send ``goal`` (an ``..._Goal`` message); the handle says whether it was accepted."""
        goal_id = uuid.uuid4().bytes
        handle = ClientGoal(goal_id, False, self, on_feedback=on_feedback)
        self._goals[goal_id] = handle
        self._watch_server()
        request = self._send.request(goal_id=_uuid(goal_id), goal=goal)
        try:
            reply = await self._send.call(request, timeout=timeout)
        except BaseException:
            self._goals.pop(goal_id, None)
            raise
        handle.accepted = bool(reply.accepted)
        if not handle.accepted:
            self._goals.pop(goal_id, None)
        elif handle.status == _S["STATUS_UNKNOWN"]:
            handle.status = _S["STATUS_ACCEPTED"]
        return handle

    async def get_result(
        self, handle: ClientGoal, *, timeout: float | None = None
    ) -> tuple[int, Any]:
        """The terminal status and result, or (:data:`STATUS_LOST`, an empty result)
        once the server has been gone for ``server_timeout``."""
        request = self._result.request(goal_id=_uuid(handle.goal_id))
        call = asyncio.ensure_future(self._result.call(request, timeout=timeout or 1e9))
        lost = asyncio.ensure_future(handle.lost.wait())
        try:
            await asyncio.wait((call, lost), return_when=asyncio.FIRST_COMPLETED)
        finally:
            answered = call.done()
            call.cancel()
            lost.cancel()
            self._goals.pop(handle.goal_id, None)
        if not answered:
            handle.status = STATUS_LOST
            return handle.status, self._result_type()
        reply = call.result()
        handle.status = int(reply.status)
        return handle.status, reply.result

    async def cancel(self, handle: ClientGoal, *, timeout: float = 10.0) -> Any:
        info = dds_type("action_msgs/msg/GoalInfo")(goal_id=_uuid(handle.goal_id))
        return await self._cancel.call(self._cancel.request(goal_info=info), timeout=timeout)

    def _on_feedback(self, sample: Any) -> None:
        handle = self._goals.get(_goal_id(sample.goal_id))
        if handle is not None and handle.on_feedback is not None:
            handle.on_feedback(sample.feedback)

    def _on_status(self, sample: Any) -> None:
        for entry in sample.status_list:
            goal_id = _goal_id(entry.goal_info.goal_id)
            handle = self._goals.get(goal_id)
            if handle is not None:
                handle.status = int(entry.status)
            elif int(entry.status) in _TERMINAL:
                self.abandoned.pop(goal_id, None)

    # -- a server that goes away and comes back -------------------------------------------
    def _watch_server(self) -> None:
        if self._watch is None or self._watch.done():
            self._watch = asyncio.get_running_loop().create_task(
                self._watching(), name=f"action client {self.names['send_goal']}"
            )

    async def _watching(self) -> None:
        """While goals run or wait for a cancel: lose them when the server is gone for
        ``server_timeout``, cancel the lost ones whenever it is there."""
        loop = asyncio.get_running_loop()
        gone_since: float | None = None
        while self._goals or self.abandoned:
            await asyncio.sleep(min(0.5, self.server_timeout / 4))
            if self.is_ready():
                gone_since = None
                for goal_id in [g for g, answered in self.abandoned.items() if not answered]:
                    await self._recancel(goal_id)
                continue
            self.abandoned = dict.fromkeys(self.abandoned, False)  # ask a returning server
            gone_since = loop.time() if gone_since is None else gone_since
            if loop.time() - gone_since >= self.server_timeout:
                self._lose_goals()

    def _lose_goals(self) -> None:
        for goal_id, handle in list(self._goals.items()):
            if not handle.accepted or handle.lost.is_set():
                continue
            handle.text = (
                f"action server {self.names['send_goal'].rpartition('/_action')[0]} "
                f"gone for {self.server_timeout:g} s"
            )
            handle.lost.set()
            self.abandoned[goal_id] = False
            while len(self.abandoned) > MAX_ABANDONED:
                del self.abandoned[next(iter(self.abandoned))]

    async def _recancel(self, goal_id: bytes) -> None:
        info = dds_type("action_msgs/msg/GoalInfo")(goal_id=_uuid(goal_id))
        try:
            reply = await self._cancel.call(
                self._cancel.request(goal_info=info), timeout=self.server_timeout
            )
        except HubError as exc:  # asked again on the next round
            log.debug("action %s: cancel of a lost goal: %s", self.names["cancel_goal"], exc)
            return
        code = int(reply.return_code)
        if code in (_CANCEL["ERROR_UNKNOWN_GOAL_ID"], _CANCEL["ERROR_GOAL_TERMINATED"]):
            self.abandoned.pop(goal_id, None)
        elif goal_id in self.abandoned:  # until the status topic says it has ended
            self.abandoned[goal_id] = True

    async def close(self) -> None:
        if self._watch is not None:
            self._watch.cancel()
            await asyncio.gather(self._watch, return_exceptions=True)
            self._watch = None
        for client in (self._send, self._result, self._cancel):
            await client.close()
        self.node.remove(self._feedback, self._status)
        self._goals.clear()
