"""Hub messages with PlanSys2's field names and constants (plansys2_msgs).

Field names, constants and types match the ROS 2 messages so that a recorded run can
be written to a bag as ``plansys2_msgs/msg/...`` and read by ROS tools, and so that a
PlanSys2 user recognises every field. Stamps are float seconds of the hub's clock
(a ROS ``builtin_interfaces/Time`` is produced when writing bags).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import IntEnum


class ExecutionType(IntEnum):
    """``ActionExecution.type`` (int16 in ROS)."""

    REQUEST = 1
    RESPONSE = 2
    CONFIRM = 3
    REJECT = 4
    FEEDBACK = 5
    FINISH = 6
    CANCEL = 7


class ActionStatus(IntEnum):
    """``ActionExecutionInfo.status``."""

    NOT_EXECUTED = 1
    EXECUTING = 2
    FAILED = 3
    SUCCEEDED = 4
    CANCELLED = 5


class PerformerState(IntEnum):
    """``ActionPerformerStatus.state``."""

    NOT_READY = 0
    READY = 1
    RUNNING = 2
    FAILURE = 4


@dataclass(frozen=True)
class ActionExecution:
    """One auction / execution message on ``actions_hub``.

    ``node_id`` is the performer's node name (empty on a REQUEST). ``bid`` is this
    project's extension for best-bid auctions: a performer's cost for the action
    (``None``: no cost given, the PlanSys2 first-responder rule applies).
    ``request_id`` identifies one action instance so two plans that run the same
    action text at once are never confused; PlanSys2 matches on the action text
    alone, which is what an empty ``request_id`` means.
    """

    type: ExecutionType
    node_id: str
    action: str
    arguments: tuple[str, ...] = ()
    success: bool = False
    completion: float = 0.0
    status: str = ""
    bid: float | None = None
    request_id: str = ""


def action_execution(
    kind: ExecutionType,
    node_id: str,
    action: str,
    arguments: tuple[str, ...],
    *,
    success: bool = False,
    completion: float = 0.0,
    status: str = "",
    bid: float | None = None,
    request_id: str = "",
) -> ActionExecution:
    """``ActionExecution(...)`` at a third of the cost, for the auction's hot paths
    (a REQUEST to 200 performers is answered by 200 RESPONSEs and 200 REJECTs): a
    frozen dataclass's ``__init__`` sets each field through ``object.__setattr__``;
    a message made here is new and not yet shared, so its fields are filled in at once."""
    msg = _new(ActionExecution)
    msg.__dict__.update(
        type=kind,
        node_id=node_id,
        action=action,
        arguments=arguments,
        success=success,
        completion=completion,
        status=status,
        bid=bid,
        request_id=request_id,
    )
    return msg


_new = object.__new__


def readdressed(msg: ActionExecution, node_id: str) -> ActionExecution:
    """``msg`` sent to ``node_id`` instead: the end of an auction among N bidders is
    N-1 REJECTs differing only in their node, and copying one message's fields costs
    half of building each from keywords (:func:`action_execution`)."""
    copy = _new(ActionExecution)
    fields = copy.__dict__
    fields.update(msg.__dict__)
    fields["node_id"] = node_id
    return copy


@dataclass(frozen=True)
class BridgeActionExecution:
    """An :class:`ActionExecution` as ``plansys_bridge_msgs/msg/ActionExecution``.

    The PlanSys2 message (whose type lacks them) wrapped with the project's fields, as
    it travels on ``rt/plansys_bridge/actions_hub`` and is recorded on
    ``/plansys_bridge/actions_hub``.
    """

    execution: ActionExecution
    request_id: str
    has_bid: bool
    bid: float

    @classmethod
    def of(cls, msg: ActionExecution) -> BridgeActionExecution:
        """The wrapper of ``msg`` (made as :func:`action_execution` makes a message:
        every message on ``actions_hub`` over DDS is wrapped on its way out)."""
        bid = msg.bid
        wrapped = _new(cls)
        wrapped.__dict__.update(
            execution=msg,
            request_id=msg.request_id,
            has_bid=bid is not None,
            bid=0.0 if bid is None else float(bid),
        )
        return wrapped


@dataclass(frozen=True)
class ActionExecutionInfo:
    """Per-action execution state, published on ``action_execution_info``."""

    status: ActionStatus
    start_stamp: float
    status_stamp: float
    action_full_name: str
    action: str
    arguments: tuple[str, ...] = ()
    duration: float = 0.0
    completion: float = 0.0
    message_status: str = ""


def execution_info(
    status: ActionStatus,
    start_stamp: float,
    status_stamp: float,
    action_full_name: str,
    action: str,
    arguments: tuple[str, ...],
    duration: float,
    completion: float,
    message_status: str,
) -> ActionExecutionInfo:
    """``ActionExecutionInfo(...)`` filled in at once, as :func:`action_execution`
    does: the executor publishes one on every change of an action's state (at least
    its start and its end), which makes it one of the most built messages of a run."""
    msg = _new(ActionExecutionInfo)
    msg.__dict__.update(
        status=status,
        start_stamp=start_stamp,
        status_stamp=status_stamp,
        action_full_name=action_full_name,
        action=action,
        arguments=arguments,
        duration=duration,
        completion=completion,
        message_status=message_status,
    )
    return msg


@dataclass(frozen=True)
class ActionPerformerStatus:
    """Performer heartbeat (1 s), published on ``performers_status``."""

    status_stamp: float
    state: PerformerState
    action: str
    specialized_arguments: tuple[str, ...] = ()
    node_name: str = ""


def performer_status(
    stamp: float,
    state: PerformerState,
    action: str,
    specialized_arguments: tuple[str, ...],
    node_name: str,
) -> ActionPerformerStatus:
    """``ActionPerformerStatus(...)`` filled in at once, as :func:`action_execution`
    does (one status of :func:`performer_statuses`)."""
    return performer_statuses(stamp, state, ((action, specialized_arguments),), node_name)[0]


def performer_statuses(
    stamp: float,
    state: PerformerState,
    served: Iterable[tuple[str, tuple[str, ...]]],
    node_name: str,
) -> list[ActionPerformerStatus]:
    """``ActionPerformerStatus(...)`` for each ``(action, specialized_arguments)``
    served, in order, filled in at once as :func:`action_execution` does: a performer
    sends one per action it serves on every change of state (two changes per action
    it executes), all built in one call."""
    made = []
    for action, specialized_arguments in served:
        msg = _new(ActionPerformerStatus)
        msg.__dict__.update(
            status_stamp=stamp,
            state=state,
            action=action,
            specialized_arguments=specialized_arguments,
            node_name=node_name,
        )
        made.append(msg)
    return made


@dataclass(frozen=True)
class PlanItem:
    time: float
    action: str
    """The grounded action text, e.g. ``"(move r2d2 a b)"``."""
    duration: float


@dataclass(frozen=True)
class Plan:
    items: tuple[PlanItem, ...] = ()


@dataclass(frozen=True)
class Knowledge:
    """Snapshot of the problem expert, published on every change."""

    instances: tuple[str, ...] = ()
    predicates: tuple[str, ...] = ()
    functions: tuple[str, ...] = ()
    goal: str = ""


@dataclass(frozen=True)
class DotGraph:
    """The plan's DOT text coloured by action state, on ``dot_graph``."""

    text: str
    plan_id: str = ""


@dataclass(frozen=True)
class ExecutingPlan:
    """The plan being executed, on ``executing_plan``."""

    plan: Plan = field(default_factory=Plan)
    plan_id: str = ""


class Topics:
    """Topic names as PlanSys2 uses them (a DDS transport prefixes ``rt/``)."""

    ACTIONS_HUB = "actions_hub"
    PERFORMERS_STATUS = "performers_status"
    ACTION_EXECUTION_INFO = "action_execution_info"
    EXECUTING_PLAN = "executing_plan"
    KNOWLEDGE = "problem_expert/knowledge"
    DOT_GRAPH = "dot_graph"
    SIGNED = "plansys_bridge/signed"
    """Auction messages and heartbeats signed with a fleet key (hub/auth.py)."""
