"""The ROS 2 types of the hub traffic, for writing and reading bags.

The layouts come from the vendored upstream texts (:mod:`plansys_bridge.interfaces`):
``plansys2_msgs`` exactly as PlanSys2 ships it, so a bag recorded here is read by ROS 2
tools that have plansys2_msgs installed, and by any MCAP reader because rosbags embeds
the definitions in the bag.

This project adds fields PlanSys2 lacks: the auction ``bid`` and the per-action
``request_id`` of an :class:`~plansys_bridge.hub.messages.ActionExecution`, and the
``plan_id`` of an executing plan. They are kept out of the plansys2_msgs types (so
those stay identical to PlanSys2's) and recorded on a second topic with a project
type, ``plansys_bridge_msgs/msg/ActionExecution`` / ``ExecutingPlan``, that wraps the
PlanSys2 message. ``DotGraph.plan_id`` is dropped: PlanSys2 publishes the graph as a
``std_msgs/msg/String`` and so does the recorder.
"""

from __future__ import annotations

from plansys_bridge.interfaces.typestore import ros2_typestore

from .rosbags_api import Typestore

ACTION_EXECUTION = "plansys2_msgs/msg/ActionExecution"
ACTION_EXECUTION_INFO = "plansys2_msgs/msg/ActionExecutionInfo"
ACTION_PERFORMER_STATUS = "plansys2_msgs/msg/ActionPerformerStatus"
PLAN_ITEM = "plansys2_msgs/msg/PlanItem"
PLAN = "plansys2_msgs/msg/Plan"
KNOWLEDGE = "plansys2_msgs/msg/Knowledge"
STRING = "std_msgs/msg/String"
BRIDGE_ACTION_EXECUTION = "plansys_bridge_msgs/msg/ActionExecution"
BRIDGE_EXECUTING_PLAN = "plansys_bridge_msgs/msg/ExecutingPlan"


def hub_typestore() -> Typestore:
    """The project's ROS 2 typestore (the vendored interfaces, built once)."""
    return ros2_typestore()
