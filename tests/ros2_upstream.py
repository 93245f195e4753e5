"""ROS 2 types and a service client written for the tests from upstream's texts.

Independent peers of the project's ROS 2 services and actions: nothing here comes from
the project's generated types. Each class is typed from its upstream ``.msg`` text
(builtin_interfaces Time/Duration, unique_identifier_msgs/UUID, std_msgs/Empty,
action_msgs GoalInfo/GoalStatus/GoalStatusArray and srv/CancelGoal, plansys2_msgs
Param/Node/PlanItem/Plan/ActionExecutionInfo) with ROS 2's DDS type names. Service
samples carry rmw_cyclonedds' request header first (``cdds_request_header_t {uint64_t
guid; int64_t seq;}``, rmw_cyclonedds_cpp/src/rmw_node.cpp), and travel on
``rq/<service>Request`` / ``rr/<service>Reply``.
"""

import asyncio
import types
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

from cyclonedds.core import Policy, Qos
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import (
    array,
    float32,
    float64,
    int8,
    int32,
    int64,
    sequence,
    uint8,
    uint32,
    uint64,
)
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Duration_(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Empty_(IdlStruct, typename="std_msgs::msg::dds_::Empty_"):
    structure_needs_at_least_one_member: uint8 = 0


@dataclass
class UUID_(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: array[uint8, 16] = field(default_factory=lambda: [0] * 16)


@dataclass
class GoalInfo_(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID_ = field(default_factory=UUID_)
    stamp: Time_ = field(default_factory=Time_)


@dataclass
class GoalStatus_(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    goal_info: GoalInfo_ = field(default_factory=GoalInfo_)
    status: int8 = 0


@dataclass
class GoalStatusArray_(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: sequence[GoalStatus_] = field(default_factory=list)


@dataclass
class CancelGoalRequest_(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    guid: uint64 = 0
    seq: int64 = 0
    goal_info: GoalInfo_ = field(default_factory=GoalInfo_)


@dataclass
class CancelGoalResponse_(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    guid: uint64 = 0
    seq: int64 = 0
    return_code: int8 = 0
    goals_canceling: sequence[GoalInfo_] = field(default_factory=list)


# action_msgs/msg/GoalStatus.msg
ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = 1, 2, 3, 4, 5, 6


@dataclass
class Param_(IdlStruct, typename="plansys2_msgs::msg::dds_::Param_"):
    name: str = ""
    type: str = ""
    sub_types: sequence[str] = field(default_factory=list)


@dataclass
class Node_(IdlStruct, typename="plansys2_msgs::msg::dds_::Node_"):
    node_type: uint8 = 0
    expression_type: uint8 = 0
    modifier_type: uint8 = 0
    node_id: uint32 = 0
    children: sequence[uint32] = field(default_factory=list)
    name: str = ""
    parameters: sequence[Param_] = field(default_factory=list)
    value: float64 = 0.0
    negate: bool = False


PREDICATE = 5  # plansys2_msgs/msg/Node.msg


@dataclass
class PlanItem_(IdlStruct, typename="plansys2_msgs::msg::dds_::PlanItem_"):
    time: float32 = 0.0
    action: str = ""
    duration: float32 = 0.0


@dataclass
class Plan_(IdlStruct, typename="plansys2_msgs::msg::dds_::Plan_"):
    items: sequence[PlanItem_] = field(default_factory=list)


@dataclass
class ActionExecutionInfo_(IdlStruct, typename="plansys2_msgs::msg::dds_::ActionExecutionInfo_"):
    status: int8 = 0
    start_stamp: Time_ = field(default_factory=Time_)
    status_stamp: Time_ = field(default_factory=Time_)
    action_full_name: str = ""
    action: str = ""
    arguments: sequence[str] = field(default_factory=list)
    duration: Duration_ = field(default_factory=Duration_)
    completion: float32 = 0.0
    message_status: str = ""


# std_msgs/msg/Header: "builtin_interfaces/Time stamp / string frame_id"
@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_ = field(default_factory=Time_)
    frame_id: str = ""


# geometry_msgs/msg/Point, Quaternion, Pose, PoseStamped (ros2/common_interfaces)
@dataclass
class Point_(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion_(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose_(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point_ = field(default_factory=Point_)
    orientation: Quaternion_ = field(default_factory=Quaternion_)


@dataclass
class PoseStamped_(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header_ = field(default_factory=Header_)
    pose: Pose_ = field(default_factory=Pose_)


def _struct(name: str, typename: str, fields: list[tuple[str, Any, Any]]) -> type:
    """``@dataclass class name(IdlStruct, typename=...)`` with ``fields`` (name, type,
    default factory), as written by hand above."""

    def body(ns: dict[str, Any]) -> None:
        ns["__annotations__"] = {f: t for f, t, _ in fields}
        ns.update({f: field(default_factory=make) for f, _, make in fields})

    return dataclass(types.new_class(name, (IdlStruct,), {"typename": typename}, body))


def action_types(package: str, action: str, goal: type, result: type, feedback: type) -> Any:
    """rosidl's messages derived from an action (``<Action>_SendGoal_Request_`` =
    request header + goal_id + goal, ...), as rmw_cyclonedds carries them."""
    prefix = f"{package}::action::dds_::{action}_"
    header: list[tuple[str, Any, Any]] = [("guid", uint64, int), ("seq", int64, int)]
    made = {
        "SendGoalRequest_": [*header, ("goal_id", UUID_, UUID_), ("goal", goal, goal)],
        "SendGoalResponse_": [*header, ("accepted", bool, bool), ("stamp", Time_, Time_)],
        "GetResultRequest_": [*header, ("goal_id", UUID_, UUID_)],
        "GetResultResponse_": [*header, ("status", int8, int), ("result", result, result)],
        "FeedbackMessage_": [("goal_id", UUID_, UUID_), ("feedback", feedback, feedback)],
    }
    names = {
        "SendGoalRequest_": "SendGoal_Request_",
        "SendGoalResponse_": "SendGoal_Response_",
        "GetResultRequest_": "GetResult_Request_",
        "GetResultResponse_": "GetResult_Response_",
        "FeedbackMessage_": "FeedbackMessage_",
    }
    return SimpleNamespace(
        **{k: _struct(k, prefix + names[k], fields) for k, fields in made.items()}
    )


def qos(depth: int = 10, latched: bool = False) -> Qos:
    """rmw_qos_profile_services_default / _default (or the latched action status), XCDR1."""
    return Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.History.KeepLast(depth),
        Policy.Durability.TransientLocal if latched else Policy.Durability.Volatile,
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


class RawClient:
    """A ROS 2 service client as rmw_cyclonedds frames one, on a plain participant."""

    def __init__(self, dp: Any, service: str, request_type: type, reply_type: type) -> None:
        self.writer = DataWriter(dp, Topic(dp, f"rq{service}Request", request_type), qos())
        self.reader = DataReader(dp, Topic(dp, f"rr{service}Reply", reply_type), qos())
        # rmw_send_request: header.guid is the request writer's instance handle
        self.guid = self.writer.instance_handle & 0xFFFF_FFFF_FFFF_FFFF
        self.request_type = request_type
        self.seq = 0

    async def wait_for_service(self, timeout: float = 10.0) -> None:
        async with asyncio.timeout(timeout):
            while (
                self.writer.get_publication_matched_status().current_count == 0
                or self.reader.get_subscription_matched_status().current_count == 0
            ):
                await asyncio.sleep(0.01)

    async def call(self, timeout: float = 10.0, **fields: Any) -> Any:
        await self.wait_for_service(timeout)
        self.seq += 1
        seq = self.seq
        self.writer.write(self.request_type(guid=self.guid, seq=seq, **fields))
        async with asyncio.timeout(timeout):
            while True:
                for sample in self.reader.take(N=10):
                    if sample.guid == self.guid and sample.seq == seq:
                        return sample
                await asyncio.sleep(0.005)
