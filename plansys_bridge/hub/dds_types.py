"""The hub's messages as DDS types, named and laid out the way ROS 2 puts them on the wire.

ROS 2 over DDS names a message type ``pkg::msg::dds_::Type_`` and serialises it as
XCDR1 little-endian; a struct's fields keep the ``.msg`` order and types
(``int16 type``, ``float32 completion``, ``string[]`` as ``sequence<string>``,
``builtin_interfaces/Time`` as ``{int32 sec, uint32 nanosec}``). The
``plansys2_msgs`` types here mirror the ``.msg`` texts in
:mod:`plansys_bridge.monitoring.msgs`, so a ROS 2 node with plansys2_msgs installed
could read and write the same topics. The ``plansys_bridge_msgs`` types wrap a
PlanSys2 message with this project's extra fields, exactly as recorded bags do.

This module deliberately has no ``from __future__ import annotations``: cyclonedds
resolves field annotations by evaluating their names in this module, which fails
for postponed (string) annotations of builtins such as ``str``.
"""

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cyclonedds.idl import IdlStruct

if TYPE_CHECKING:
    # What the fields hold in Python, for the type checker; cyclonedds needs its markers.
    from builtins import float as float32
    from builtins import float as float64
    from builtins import int as int8
    from builtins import int as int16
    from builtins import int as int32
    from builtins import int as uint8
    from builtins import int as uint32
    from builtins import list as sequence
else:
    from cyclonedds.idl.types import float32, float64, int8, int16, int32, sequence, uint8, uint32

__all__ = [
    "ActionExecutionInfo_",
    "ActionExecution_",
    "ActionPerformerStatus_",
    "BridgeActionExecution_",
    "BridgeExecutingPlan_",
    "Duration_",
    "Knowledge_",
    "PlanItem_",
    "Plan_",
    "String_",
    "Time_",
]


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Duration_(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str = ""


@dataclass
class ActionExecution_(IdlStruct, typename="plansys2_msgs::msg::dds_::ActionExecution_"):
    type: int16 = 0
    node_id: str = ""
    action: str = ""
    arguments: sequence[str] = field(default_factory=list)
    success: bool = False
    completion: float32 = 0.0
    status: str = ""


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


@dataclass
class ActionPerformerStatus_(
    IdlStruct, typename="plansys2_msgs::msg::dds_::ActionPerformerStatus_"
):
    status_stamp: Time_ = field(default_factory=Time_)
    state: uint8 = 0
    action: str = ""
    specialized_arguments: sequence[str] = field(default_factory=list)
    node_name: str = ""


@dataclass
class PlanItem_(IdlStruct, typename="plansys2_msgs::msg::dds_::PlanItem_"):
    time: float32 = 0.0
    action: str = ""
    duration: float32 = 0.0


@dataclass
class Plan_(IdlStruct, typename="plansys2_msgs::msg::dds_::Plan_"):
    items: sequence[PlanItem_] = field(default_factory=list)


@dataclass
class Knowledge_(IdlStruct, typename="plansys2_msgs::msg::dds_::Knowledge_"):
    instances: sequence[str] = field(default_factory=list)
    predicates: sequence[str] = field(default_factory=list)
    functions: sequence[str] = field(default_factory=list)
    goal: str = ""


@dataclass
class BridgeActionExecution_(
    IdlStruct, typename="plansys_bridge_msgs::msg::dds_::ActionExecution_"
):
    execution: ActionExecution_ = field(default_factory=ActionExecution_)
    request_id: str = ""
    has_bid: bool = False
    bid: float64 = 0.0


@dataclass
class BridgeExecutingPlan_(IdlStruct, typename="plansys_bridge_msgs::msg::dds_::ExecutingPlan_"):
    plan_id: str = ""
    plan: Plan_ = field(default_factory=Plan_)
