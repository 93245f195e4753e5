"""ROS 2 message definitions of the hub traffic, for writing and reading bags.

The ``plansys2_msgs`` texts follow PlanSys2's message files (field names, constants,
and types as DESIGN.md lists them: ``ActionExecution.type`` is int16), so a bag
recorded here is read by ROS 2 tools that have plansys2_msgs installed, and by any
MCAP reader because the definitions are embedded in the bag.

This project adds two fields PlanSys2 lacks: the auction ``bid`` and the per-action
``request_id`` of an :class:`~plansys_bridge.hub.messages.ActionExecution`, and the
``plan_id`` of an executing plan. They are kept out of the plansys2_msgs types (so
those stay identical to PlanSys2's) and recorded on a second topic with a project
type, ``plansys_bridge_msgs/msg/ActionExecution`` / ``ExecutingPlan``, that wraps the
PlanSys2 message. ``DotGraph.plan_id`` is dropped: PlanSys2 publishes the graph as a
``std_msgs/msg/String`` and so does the recorder.
"""

from __future__ import annotations

from functools import cache

from .rosbags_api import Stores, Typestore, get_types_from_msg, get_typestore

ACTION_EXECUTION = "plansys2_msgs/msg/ActionExecution"
ACTION_EXECUTION_INFO = "plansys2_msgs/msg/ActionExecutionInfo"
ACTION_PERFORMER_STATUS = "plansys2_msgs/msg/ActionPerformerStatus"
PLAN_ITEM = "plansys2_msgs/msg/PlanItem"
PLAN = "plansys2_msgs/msg/Plan"
KNOWLEDGE = "plansys2_msgs/msg/Knowledge"
STRING = "std_msgs/msg/String"
BRIDGE_ACTION_EXECUTION = "plansys_bridge_msgs/msg/ActionExecution"
BRIDGE_EXECUTING_PLAN = "plansys_bridge_msgs/msg/ExecutingPlan"

MSG_DEFINITIONS: dict[str, str] = {
    ACTION_EXECUTION: """\
int16 REQUEST = 1
int16 RESPONSE = 2
int16 CONFIRM = 3
int16 REJECT = 4
int16 FEEDBACK = 5
int16 FINISH = 6
int16 CANCEL = 7

int16 type
string node_id
string action
string[] arguments
bool success
float32 completion
string status
""",
    ACTION_EXECUTION_INFO: """\
int8 NOT_EXECUTED = 1
int8 EXECUTING = 2
int8 FAILED = 3
int8 SUCCEEDED = 4
int8 CANCELLED = 5

int8 status
builtin_interfaces/Time start_stamp
builtin_interfaces/Time status_stamp
string action_full_name
string action
string[] arguments
builtin_interfaces/Duration duration
float32 completion
string message_status
""",
    ACTION_PERFORMER_STATUS: """\
uint8 NOT_READY = 0
uint8 READY = 1
uint8 RUNNING = 2
uint8 FAILURE = 4

builtin_interfaces/Time status_stamp
uint8 state
string action
string[] specialized_arguments
string node_name
""",
    PLAN_ITEM: """\
float32 time
string action
float32 duration
""",
    PLAN: """\
plansys2_msgs/PlanItem[] items
""",
    KNOWLEDGE: """\
string[] instances
string[] predicates
string[] functions
string goal
""",
    BRIDGE_ACTION_EXECUTION: """\
# A plansys2_msgs/ActionExecution with this project's auction fields.
plansys2_msgs/ActionExecution execution
string request_id
bool has_bid
float64 bid
""",
    BRIDGE_EXECUTING_PLAN: """\
# The executing plan with the id that tells concurrent plans apart.
string plan_id
plansys2_msgs/Plan plan
""",
}


def register_types(store: Typestore) -> None:
    """Register the plansys2_msgs and project types in ``store``."""
    types = {}
    for name, text in MSG_DEFINITIONS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)


@cache
def hub_typestore() -> Typestore:
    """ROS 2 Humble types plus the hub's message types (built once)."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    register_types(store)
    return store
