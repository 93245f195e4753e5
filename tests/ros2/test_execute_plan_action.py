"""PlanSys2's ExecutePlan action, driven by an independent ROS 2 action client.

The client is a plain Cyclone DDS program with types typed from the upstream texts
(plansys2_msgs/action/ExecutePlan.action and the messages in ros2_upstream.py), framed
as rcl_action and rmw_cyclonedds do: ``/execute_plan/_action/send_goal`` and
``get_result`` services with the request header, ``rt/execute_plan/_action/feedback``,
rosidl's derived ``ExecutePlan_SendGoal_Request_`` (goal_id + goal) and the rest.
"""

import asyncio
import random
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import sequence
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from ros2_upstream import (
    CANCELED,
    SUCCEEDED,
    UUID_,
    ActionExecutionInfo_,
    CancelGoalRequest_,
    CancelGoalResponse_,
    GoalInfo_,
    Plan_,
    PlanItem_,
    RawClient,
    action_types,
    qos,
)

from plansys_bridge.clock import WallClock
from plansys_bridge.execution.executor import Executor
from plansys_bridge.hub.hub import Hub
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer
from plansys_bridge.ros2.executor_action import ExecutePlanServer
from plansys_bridge.ros2.node import Ros2Node

pytestmark = [pytest.mark.timeout(90), pytest.mark.usefixtures("no_leaks")]

DOMAIN = Path(__file__).resolve().parents[2] / "configs" / "pddl" / "flat_navigation.pddl"


@dataclass
class Goal_(IdlStruct, typename="plansys2_msgs::action::dds_::ExecutePlan_Goal_"):
    plan: Plan_ = field(default_factory=Plan_)


@dataclass
class Result_(IdlStruct, typename="plansys2_msgs::action::dds_::ExecutePlan_Result_"):
    success: bool = False
    action_execution_status: sequence[ActionExecutionInfo_] = field(default_factory=list)


@dataclass
class Feedback_(IdlStruct, typename="plansys2_msgs::action::dds_::ExecutePlan_Feedback_"):
    action_execution_status: sequence[ActionExecutionInfo_] = field(default_factory=list)


EXECUTE_PLAN = action_types("plansys2_msgs", "ExecutePlan", Goal_, Result_, Feedback_)
SendGoalRequest_ = EXECUTE_PLAN.SendGoalRequest_
SendGoalResponse_ = EXECUTE_PLAN.SendGoalResponse_
GetResultRequest_ = EXECUTE_PLAN.GetResultRequest_
GetResultResponse_ = EXECUTE_PLAN.GetResultResponse_
FeedbackMessage_ = EXECUTE_PLAN.FeedbackMessage_


SUCCEEDED_ACTION = 4  # ActionExecutionInfo.msg: int8 SUCCEEDED=4


def knowledge() -> ProblemExpert:
    k = ProblemExpert(parse_domain_files([DOMAIN]))
    for name, typ in {"r1": "robot", "hall": "room", "kitchen": "room", "bedroom": "room"}.items():
        k.add_instance(name, typ)
    for fact in ("(robot_at r1 hall)", "(connected hall kitchen)", "(connected kitchen bedroom)"):
        k.add_predicate(fact)
    k.set_function("(= (travel_time hall kitchen) 4)")
    k.set_function("(= (travel_time kitchen bedroom) 3)")
    return k


PLAN = Plan_(
    [
        PlanItem_(0.0, "(move r1 hall kitchen)", 4.0),
        PlanItem_(4.001, "(move r1 kitchen bedroom)", 3.0),
    ]
)


def run_action(body: Any, *, duration: float = 1.0) -> Any:
    async def main() -> Any:
        domain = random.SystemRandom().randint(1, 232)
        hub = Hub(clock=WallClock(time_scale=0.05))
        await hub.start()
        kb = knowledge()
        robot = SimulatedPerformer(
            PerformerContext(hub, hub.clock, knowledge=kb),
            "r1_base",
            {"move": ["r1"]},
            default_duration=duration,
            feedback_period=0.5,
        )
        await robot.start()
        node = Ros2Node(domain, name="executor")
        await node.start()
        executor = Executor(hub, kb.domain, kb)
        server = ExecutePlanServer(node, executor)
        dp = DomainParticipant(domain)
        base = "/execute_plan/_action"
        send = RawClient(dp, f"{base}/send_goal", SendGoalRequest_, SendGoalResponse_)
        result = RawClient(dp, f"{base}/get_result", GetResultRequest_, GetResultResponse_)
        cancel = RawClient(dp, f"{base}/cancel_goal", CancelGoalRequest_, CancelGoalResponse_)
        feedback = DataReader(dp, Topic(dp, f"rt{base}/feedback", FeedbackMessage_), qos())
        try:
            return await body(send, result, cancel, feedback, kb)
        finally:
            dp.__del__()
            await server.close()
            await node.close()
            await robot.stop()
            await hub.close()

    return asyncio.run(main())


def test_execute_plan_gives_feedback_and_the_result() -> None:
    async def body(send: Any, result: Any, _cancel: Any, feedback: Any, kb: Any) -> Any:
        goal_id = UUID_(list(uuid.uuid4().bytes))
        reply = await send.call(goal_id=goal_id, goal=Goal_(PLAN))
        assert reply.accepted
        outcome = await result.call(timeout=30, goal_id=goal_id)
        return outcome, feedback.take(N=1000), kb

    outcome, feedback, kb = run_action(body)
    assert outcome.status == SUCCEEDED
    assert outcome.result.success
    statuses = {i.action_full_name: i.status for i in outcome.result.action_execution_status}
    assert statuses == {
        "(move r1 hall kitchen)": SUCCEEDED_ACTION,
        "(move r1 kitchen bedroom)": SUCCEEDED_ACTION,
    }
    assert feedback, "no feedback"
    names = {i.action_full_name for f in feedback for i in f.feedback.action_execution_status}
    assert "(move r1 hall kitchen)" in names
    assert kb.exist_predicate("(robot_at r1 bedroom)")


def test_cancel_and_a_plan_that_does_not_parse() -> None:
    async def body(send: Any, result: Any, cancel: Any, _feedback: Any, _kb: Any) -> Any:
        bad = UUID_(list(uuid.uuid4().bytes))
        rejected = await send.call(goal_id=bad, goal=Goal_(Plan_([PlanItem_(0, "move r1 (", 1)])))
        goal_id = UUID_(list(uuid.uuid4().bytes))
        reply = await send.call(goal_id=goal_id, goal=Goal_(PLAN))
        await asyncio.sleep(0.1)
        cancelled = await cancel.call(goal_info=GoalInfo_(goal_id=goal_id))
        outcome = await result.call(timeout=30, goal_id=goal_id)
        return rejected, reply, cancelled, outcome, bytes(goal_id.uuid)

    rejected, reply, cancelled, outcome, goal_id = run_action(body, duration=100.0)
    assert not rejected.accepted
    assert reply.accepted
    assert cancelled.return_code == 0
    assert [bytes(g.goal_id.uuid) for g in cancelled.goals_canceling] == [goal_id]
    assert outcome.status == CANCELED
    assert not outcome.result.success
