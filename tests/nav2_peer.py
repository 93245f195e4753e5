"""An independent Nav2 ``NavigateToPose`` action server for the Nav2 tests.

A plain Cyclone DDS program, not the project's action code. Its types are typed
here from the upstream texts (nav2_msgs/action/NavigateToPose.action, jazzy) and in
ros2_upstream.py (geometry_msgs, std_msgs, builtin_interfaces,
unique_identifier_msgs, action_msgs), framed as rcl_action and rmw_cyclonedds put
them on the wire: ``<action>/_action/{send_goal,get_result,cancel_goal}`` services
with the ``{uint64 guid; int64 seq}`` request header, ``rt/<action>/_action/feedback``
and ``rt/<action>/_action/status`` topics, and rosidl's derived action messages
(``NavigateToPose_SendGoal_Request_`` = goal_id + goal, ...).
"""

import asyncio
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, int16, uint16
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from ros2_upstream import (
    ABORTED,
    CANCELED,
    EXECUTING,
    SUCCEEDED,
    UUID_,
    CancelGoalRequest_,
    CancelGoalResponse_,
    Duration_,
    GoalInfo_,
    GoalStatus_,
    GoalStatusArray_,
    PoseStamped_,
    Time_,
    action_types,
    qos,
)

__all__ = ["Feedback_", "Goal_", "RawNavigateToPoseServer", "Result_", "ServerThread"]


# -- upstream types, typed from the .msg/.action/.srv texts -----------------------------
@dataclass
class Goal_(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_Goal_"):
    pose: PoseStamped_ = field(default_factory=PoseStamped_)
    behavior_tree: str = ""


@dataclass
class Result_(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_Result_"):
    error_code: uint16 = 0
    error_msg: str = ""


@dataclass
class Feedback_(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_Feedback_"):
    current_pose: PoseStamped_ = field(default_factory=PoseStamped_)
    navigation_time: Duration_ = field(default_factory=Duration_)
    estimated_time_remaining: Duration_ = field(default_factory=Duration_)
    number_of_recoveries: int16 = 0
    distance_remaining: float32 = 0.0


NAV = action_types("nav2_msgs", "NavigateToPose", Goal_, Result_, Feedback_)
SendGoalRequest_ = NAV.SendGoalRequest_
SendGoalResponse_ = NAV.SendGoalResponse_
GetResultRequest_ = NAV.GetResultRequest_
GetResultResponse_ = NAV.GetResultResponse_
FeedbackMessage_ = NAV.FeedbackMessage_


class RawNavigateToPoseServer:
    """NavigateToPose as a ROS 2 action server on rmw_cyclonedds would serve it.

    Goals to x=4 succeed after feedback 3, 2, 1, 0 m; goals to x=9 are ABORTED with
    error_code 204; other goals run until cancelled.
    """

    def __init__(
        self, domain: int, action: str = "/navigate_to_pose", *, period: float = 0.05
    ) -> None:
        self.period = period
        """Seconds between two steps of a goal (feedback, the next metre)."""
        self.dp = dp = DomainParticipant(domain)
        base = f"{action}/_action"

        def service(name: str, req: type, rep: type) -> tuple[Any, Any]:
            reader = DataReader(dp, Topic(dp, f"rq{base}/{name}Request", req), qos())
            writer = DataWriter(dp, Topic(dp, f"rr{base}/{name}Reply", rep), qos())
            return reader, writer

        self.send = service("send_goal", SendGoalRequest_, SendGoalResponse_)
        self.result = service("get_result", GetResultRequest_, GetResultResponse_)
        self.cancel = service("cancel_goal", CancelGoalRequest_, CancelGoalResponse_)
        self.feedback = DataWriter(dp, Topic(dp, f"rt{base}/feedback", FeedbackMessage_), qos())
        self.status = DataWriter(
            dp, Topic(dp, f"rt{base}/status", GoalStatusArray_), qos(1, latched=True)
        )
        self.goals: dict[bytes, dict[str, Any]] = {}
        self.cancels: list[bytes] = []
        self.waiting: list[Any] = []
        self._task: asyncio.Task[None] | None = None

    def hold(self, goal_id: bytes, x: float) -> None:
        """Run ``goal_id`` (to ``x``) as if it had been sent before: a server back
        on the network still driving a goal its client gave up on."""
        self.goals[goal_id] = {"x": x, "status": EXECUTING, "t": time.monotonic(), "left": 3}
        self._publish_status()

    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self._serve())

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            await asyncio.gather(self._task, return_exceptions=True)
        self.dp.__del__()

    def _publish_status(self) -> None:
        self.status.write(
            GoalStatusArray_(
                [
                    GoalStatus_(GoalInfo_(UUID_(list(gid))), g["status"])
                    for gid, g in self.goals.items()
                ]
            )
        )

    async def _serve(self) -> None:
        while True:
            now = time.monotonic()
            for req in self.send[0].take(N=10):
                gid = bytes(req.goal_id.uuid)
                x = req.goal.pose.pose.position.x
                self.goals[gid] = {"x": x, "status": EXECUTING, "t": now, "left": 3}
                self.send[1].write(
                    SendGoalResponse_(req.guid, req.seq, True, Time_(int(time.time())))
                )
                self._publish_status()
            for req in self.cancel[0].take(N=10):
                gid = bytes(req.goal_info.goal_id.uuid)
                self.cancels.append(gid)
                goal = self.goals.get(gid)
                canceling = []
                if goal is not None and goal["status"] == EXECUTING:
                    goal["status"] = CANCELED
                    goal["result"] = Result_()
                    canceling = [GoalInfo_(UUID_(list(gid)))]
                self.cancel[1].write(CancelGoalResponse_(req.guid, req.seq, 0, canceling))
                self._publish_status()
            self.waiting.extend(self.result[0].take(N=10))
            for gid, goal in self.goals.items():
                if goal["status"] != EXECUTING or now - goal["t"] < self.period:
                    continue
                goal["t"] = now
                if goal["x"] == 9.0:
                    goal["status"], goal["result"] = ABORTED, Result_(204, "no valid path")
                elif goal["x"] == 4.0:
                    fb = Feedback_(distance_remaining=float(goal["left"]))
                    self.feedback.write(FeedbackMessage_(UUID_(list(gid)), fb))
                    if goal["left"] == 0:
                        goal["status"], goal["result"] = SUCCEEDED, Result_()
                    goal["left"] -= 1
                else:
                    fb = Feedback_(distance_remaining=40.0)
                    self.feedback.write(FeedbackMessage_(UUID_(list(gid)), fb))
                self._publish_status()
            for req in list(self.waiting):
                goal = self.goals.get(bytes(req.goal_id.uuid))
                if goal is not None and goal["status"] in (SUCCEEDED, CANCELED, ABORTED):
                    self.result[1].write(
                        GetResultResponse_(req.guid, req.seq, goal["status"], goal["result"])
                    )
                    self.waiting.remove(req)
            await asyncio.sleep(0.005)


class ServerThread:
    """A :class:`RawNavigateToPoseServer` on its own thread and event loop, for tests
    whose loop is made by a harness (the performer contract): ``start()``, ``stop()``.

    The domain is opened first by a project node, as the performers' tests do, so
    Cyclone uses the project's loopback configuration."""

    def __init__(self, domain: int, *, period: float = 0.05) -> None:
        self.domain = domain
        self.period = period
        self.server: RawNavigateToPoseServer | None = None
        self._up = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=asyncio.run, args=(self._serve(),), daemon=True)

    async def _serve(self) -> None:
        from plansys_bridge.ros2.node import Ros2Node

        self._loop, self._stop = asyncio.get_running_loop(), asyncio.Event()
        node = Ros2Node(self.domain, name="nav2_peer")
        await node.start()
        self.server = RawNavigateToPoseServer(self.domain, period=self.period)
        self.server.start()
        self._up.set()
        try:
            await self._stop.wait()
        finally:
            await self.server.close()
            await node.close()

    def start(self) -> "ServerThread":
        self._thread.start()
        if not self._up.wait(30):
            raise RuntimeError("the Nav2 peer did not start in 30 s")
        return self

    def stop(self) -> None:
        if self._loop is not None and self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(30)
