"""The ``ros2_nav2`` performer against an independent NavigateToPose action server.

The server below is a plain Cyclone DDS program. Its types are typed here from the
upstream texts (nav2_msgs/action/NavigateToPose.action, jazzy; geometry_msgs Pose,
PoseStamped, Point, Quaternion; std_msgs/Header) and in ros2_upstream.py
(builtin_interfaces, unique_identifier_msgs, action_msgs), framed as rcl_action and
rmw_cyclonedds put them on the wire:
``<action>/_action/{send_goal,get_result,cancel_goal}`` services with the
``{uint64 guid; int64 seq}`` request header, ``rt/<action>/_action/feedback`` and
``rt/<action>/_action/status`` topics, and rosidl's derived action messages
(``NavigateToPose_SendGoal_Request_`` = goal_id + goal, ...).
"""

import asyncio
import random
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, int16, uint16
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from plansys_bridge_adapters.ros2_nav2.performer import Nav2Performer
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

from plansys_bridge.clock import WallClock
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import PerformerContext

pytestmark = [pytest.mark.timeout(90), pytest.mark.usefixtures("no_leaks")]

DOMAIN = Path(__file__).resolve().parents[3] / "configs" / "pddl" / "flat_navigation.pddl"


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

    def __init__(self, domain: int, action: str = "/navigate_to_pose") -> None:
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
                if goal["status"] != EXECUTING or now - goal["t"] < 0.05:
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


LOCATIONS = {
    "hall": {"x": 0.0, "y": 0.0},
    "kitchen": {"x": 4.0, "y": 1.0, "yaw": 1.57},
    "bedroom": {"x": 9.0, "y": 0.0},
    "garden": {"x": 30.0, "y": 0.0},
}


def _entry(domain: int, **extra: Any) -> dict[str, Any]:
    return {
        "kind": "ros2_nav2",
        "name": "tb3",
        "actions": {"move": ["r1"]},
        "frame_id": "map",
        "locations": LOCATIONS,
        "domain_id": domain,
        **extra,
    }


def _knowledge() -> ProblemExpert:
    k = ProblemExpert(parse_domain_files([DOMAIN]))
    k.add_instance("r1", "robot")
    for room in LOCATIONS:
        k.add_instance(room, "room")
    return k


def run_moves(script: Any) -> tuple[list[ActionExecution], RawNavigateToPoseServer]:
    """Start the peer and the performer, run ``script(hub, send)``, return the messages."""

    async def main() -> tuple[list[ActionExecution], RawNavigateToPoseServer]:
        domain = random.SystemRandom().randint(1, 232)
        hub = Hub(clock=WallClock())
        await hub.start()
        seen: list[ActionExecution] = []
        hub.subscribe(Topics.ACTIONS_HUB, lambda m: seen.append(m))
        context = PerformerContext(hub, hub.clock, knowledge=_knowledge())
        (performer,) = Nav2Performer.from_config(_entry(domain), context)
        await performer.start()  # first: its node opens the domain on the loopback config
        server = RawNavigateToPoseServer(domain)
        server.start()
        try:
            async with asyncio.timeout(20):
                while not performer.ready:
                    await asyncio.sleep(0.02)

            async def send(kind: ExecutionType, args: tuple[str, ...], rid: str) -> None:
                node = "" if kind is ExecutionType.REQUEST else "tb3"
                hub.publish(
                    Topics.ACTIONS_HUB, ActionExecution(kind, node, "move", args, request_id=rid)
                )
                await asyncio.sleep(0.01)

            await script(seen, send)
        finally:
            await performer.stop()
            await server.close()
            await hub.close()
        return seen, server

    return asyncio.run(main())


async def _finish(seen: list[ActionExecution], rid: str) -> ActionExecution:
    async with asyncio.timeout(15):
        while True:
            for m in seen:
                if m.type is ExecutionType.FINISH and m.request_id == rid:
                    return m
            await asyncio.sleep(0.01)


def test_goal_succeeds_with_feedback_from_distance_remaining() -> None:
    async def script(seen: list[ActionExecution], send: Any) -> None:
        await send(ExecutionType.REQUEST, ("r1", "hall", "kitchen"), "a")
        await send(ExecutionType.CONFIRM, ("r1", "hall", "kitchen"), "a")
        finish = await _finish(seen, "a")
        assert finish.success, finish.status
        assert finish.status == "reached kitchen"

    seen, server = run_moves(script)
    ((goal_x, goal),) = [(g["x"], g) for g in server.goals.values()]
    assert goal_x == 4.0 and goal["status"] == SUCCEEDED
    feedback = [m.completion for m in seen if m.type is ExecutionType.FEEDBACK]
    # 3, 2, 1, 0 m left of at most 3 m: 0, 1/3, 2/3, 1 (a loaded machine may merge or
    # repeat a sample, never invent one or go backwards)
    steps = [0.0, 1 / 3, 2 / 3, 1.0]
    assert feedback == sorted(feedback), feedback
    assert all(min(abs(f - s) for s in steps) < 1e-6 for f in feedback), feedback
    assert any(abs(f - 1 / 3) < 1e-6 or abs(f - 2 / 3) < 1e-6 for f in feedback), feedback


def test_aborted_goal_fails_with_the_result_code() -> None:
    async def script(seen: list[ActionExecution], send: Any) -> None:
        await send(ExecutionType.REQUEST, ("r1", "hall", "bedroom"), "b")
        await send(ExecutionType.CONFIRM, ("r1", "hall", "bedroom"), "b")
        finish = await _finish(seen, "b")
        assert not finish.success
        assert "ABORTED" in finish.status and "204" in finish.status
        assert "no valid path" in finish.status

    run_moves(script)


def test_halt_cancels_the_nav2_goal() -> None:
    async def script(seen: list[ActionExecution], send: Any) -> None:
        await send(ExecutionType.REQUEST, ("r1", "hall", "garden"), "c")
        await send(ExecutionType.CONFIRM, ("r1", "hall", "garden"), "c")
        async with asyncio.timeout(10):
            while not any(m.type is ExecutionType.FEEDBACK for m in seen):
                await asyncio.sleep(0.01)
        await send(ExecutionType.CANCEL, ("r1", "hall", "garden"), "c")
        await asyncio.sleep(0.5)

    seen, server = run_moves(script)
    (gid,) = server.goals
    assert server.cancels == [gid]
    assert server.goals[gid]["status"] == CANCELED
    assert not any(m.type is ExecutionType.FINISH for m in seen)


def test_a_destination_without_location_is_a_load_error() -> None:
    hub = Hub(clock=WallClock())
    context = PerformerContext(hub, hub.clock, knowledge=_knowledge())
    entry = _entry(5, locations={"hall": {"x": 0, "y": 0}})
    with pytest.raises(ConfigError) as err:
        Nav2Performer.from_config(entry, context, key="performers[0]")
    assert err.value.key == "performers[0].locations"
    assert "no location for 'bedroom'" in str(err.value)
