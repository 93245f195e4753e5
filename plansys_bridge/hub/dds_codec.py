"""Hub messages <-> DDS samples, and which DDS topics carry each hub topic.

Every hub topic travels on ``rt/<topic>`` with its PlanSys2 type, so a ROS 2 node sees
the traffic it expects. Where this project adds fields PlanSys2 lacks
(``ActionExecution.bid`` / ``request_id``, ``ExecutingPlan.plan_id``), the complete
message also goes, wrapped, on ``rt/plansys_bridge/<topic>`` with a
``plansys_bridge_msgs`` type: the same split the bag recorder uses
(:mod:`plansys_bridge.monitoring.msgs`), so DDS traffic and recorded bags agree.
A project receiver takes such messages from the wrapper topic only and ignores the
plain copy (see :class:`~plansys_bridge.hub.dds.DdsTransport`); plain messages from
other DDS nodes, which have no wrapper, arrive with the extra fields at their
defaults. ``DotGraph.plan_id`` is not carried (PlanSys2 and the bags use a
``std_msgs/String``), and a bare :class:`~plansys_bridge.hub.messages.Plan`
published on ``executing_plan`` arrives as an ``ExecutingPlan`` with no plan id.

Stamps are float seconds in the hub and ``builtin_interfaces/Time`` on the wire
(nanosecond resolution); ``completion`` and plan item times are ``float32`` as in
PlanSys2, so they come back rounded to single precision.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from cyclonedds.idl import IdlStruct

from plansys_bridge.errors import HubError
from plansys_bridge.hub import dds_types as T
from plansys_bridge.hub import messages as hm

__all__ = [
    "BRIDGE_PREFIX",
    "ROUTES",
    "Channel",
    "Route",
    "dds_topic_name",
    "decode",
    "encode",
    "from_idl_seconds",
    "to_idl_duration",
    "to_idl_time",
]

ROS_PREFIX = "rt/"
"""ROS 2 puts a topic ``/name`` on the DDS topic ``rt/name``."""

BRIDGE_PREFIX = "plansys_bridge/"
"""The project's wrapper topics live under this namespace (as ``/plansys_bridge`` in bags)."""

_INT32 = (-(2**31), 2**31 - 1)


def dds_topic_name(hub_topic: str, *, project: bool = False) -> str:
    """``actions_hub`` -> ``rt/actions_hub`` (``rt/plansys_bridge/actions_hub`` if project)."""
    name = hub_topic.lstrip("/")
    return ROS_PREFIX + (BRIDGE_PREFIX if project else "") + name


# -- stamps ------------------------------------------------------------------------------


def _split_seconds(seconds: float, what: str) -> tuple[int, int]:
    if not math.isfinite(seconds):
        raise HubError(f"{what} {seconds!r} is not a finite number of seconds")
    sec = math.floor(seconds)
    nanosec = round((seconds - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    if not _INT32[0] <= sec <= _INT32[1]:
        raise HubError(f"{what} {seconds!r} s does not fit builtin_interfaces (int32 seconds)")
    return int(sec), int(nanosec)


def to_idl_time(seconds: float) -> T.Time_:
    sec, nanosec = _split_seconds(seconds, "stamp")
    return T.Time_(sec=sec, nanosec=nanosec)


def to_idl_duration(seconds: float) -> T.Duration_:
    sec, nanosec = _split_seconds(seconds, "duration")
    return T.Duration_(sec=sec, nanosec=nanosec)


def from_idl_seconds(value: T.Time_ | T.Duration_) -> float:
    return value.sec + value.nanosec * 1e-9


# -- one function pair per message -------------------------------------------------------


def action_execution_to_idl(m: hm.ActionExecution) -> T.ActionExecution_:
    return T.ActionExecution_(
        type=int(m.type),
        node_id=m.node_id,
        action=m.action,
        arguments=list(m.arguments),
        success=bool(m.success),
        completion=float(m.completion),
        status=m.status,
    )


def action_execution_from_idl(
    x: T.ActionExecution_, *, request_id: str = "", bid: float | None = None
) -> hm.ActionExecution:
    return hm.ActionExecution(
        type=hm.ExecutionType(x.type),
        node_id=x.node_id,
        action=x.action,
        arguments=tuple(x.arguments),
        success=bool(x.success),
        completion=float(x.completion),
        status=x.status,
        bid=bid,
        request_id=request_id,
    )


def bridge_action_execution_to_idl(m: hm.ActionExecution) -> T.BridgeActionExecution_:
    return T.BridgeActionExecution_(
        execution=action_execution_to_idl(m),
        request_id=m.request_id,
        has_bid=m.bid is not None,
        bid=float(m.bid) if m.bid is not None else 0.0,
    )


def bridge_action_execution_from_idl(x: T.BridgeActionExecution_) -> hm.ActionExecution:
    return action_execution_from_idl(
        x.execution, request_id=x.request_id, bid=float(x.bid) if x.has_bid else None
    )


def execution_info_to_idl(m: hm.ActionExecutionInfo) -> T.ActionExecutionInfo_:
    return T.ActionExecutionInfo_(
        status=int(m.status),
        start_stamp=to_idl_time(m.start_stamp),
        status_stamp=to_idl_time(m.status_stamp),
        action_full_name=m.action_full_name,
        action=m.action,
        arguments=list(m.arguments),
        duration=to_idl_duration(m.duration),
        completion=float(m.completion),
        message_status=m.message_status,
    )


def execution_info_from_idl(x: T.ActionExecutionInfo_) -> hm.ActionExecutionInfo:
    return hm.ActionExecutionInfo(
        status=hm.ActionStatus(x.status),
        start_stamp=from_idl_seconds(x.start_stamp),
        status_stamp=from_idl_seconds(x.status_stamp),
        action_full_name=x.action_full_name,
        action=x.action,
        arguments=tuple(x.arguments),
        duration=from_idl_seconds(x.duration),
        completion=float(x.completion),
        message_status=x.message_status,
    )


def performer_status_to_idl(m: hm.ActionPerformerStatus) -> T.ActionPerformerStatus_:
    return T.ActionPerformerStatus_(
        status_stamp=to_idl_time(m.status_stamp),
        state=int(m.state),
        action=m.action,
        specialized_arguments=list(m.specialized_arguments),
        node_name=m.node_name,
    )


def performer_status_from_idl(x: T.ActionPerformerStatus_) -> hm.ActionPerformerStatus:
    return hm.ActionPerformerStatus(
        status_stamp=from_idl_seconds(x.status_stamp),
        state=hm.PerformerState(x.state),
        action=x.action,
        specialized_arguments=tuple(x.specialized_arguments),
        node_name=x.node_name,
    )


def plan_to_idl(m: hm.Plan) -> T.Plan_:
    return T.Plan_(
        items=[
            T.PlanItem_(time=float(i.time), action=i.action, duration=float(i.duration))
            for i in m.items
        ]
    )


def plan_from_idl(x: T.Plan_) -> hm.Plan:
    return hm.Plan(
        tuple(
            hm.PlanItem(time=float(i.time), action=i.action, duration=float(i.duration))
            for i in x.items
        )
    )


def executing_plan_to_idl(m: hm.ExecutingPlan) -> T.BridgeExecutingPlan_:
    return T.BridgeExecutingPlan_(plan_id=m.plan_id, plan=plan_to_idl(m.plan))


def executing_plan_from_idl(x: T.BridgeExecutingPlan_) -> hm.ExecutingPlan:
    return hm.ExecutingPlan(plan=plan_from_idl(x.plan), plan_id=x.plan_id)


def knowledge_to_idl(m: hm.Knowledge) -> T.Knowledge_:
    return T.Knowledge_(
        instances=list(m.instances),
        predicates=list(m.predicates),
        functions=list(m.functions),
        goal=m.goal,
    )


def knowledge_from_idl(x: T.Knowledge_) -> hm.Knowledge:
    return hm.Knowledge(
        instances=tuple(x.instances),
        predicates=tuple(x.predicates),
        functions=tuple(x.functions),
        goal=x.goal,
    )


# -- routing -----------------------------------------------------------------------------


@dataclass(frozen=True)
class Channel:
    """One DDS topic: its name, type, history depth, and how samples become hub messages."""

    dds_topic: str
    idl_type: type[IdlStruct]
    depth: int
    decode: Callable[[Any], object]
    project: bool
    """True for the ``plansys_bridge_msgs`` wrapper topic of a hub topic."""


@dataclass(frozen=True)
class Route:
    """How one hub topic travels: the PlanSys2 channel and, if any, the project wrapper."""

    hub_topic: str
    accepts: tuple[type, ...]
    plain: Channel
    project: Channel | None
    encode: Callable[[Any], tuple[IdlStruct, IdlStruct | None]]

    @property
    def channels(self) -> tuple[Channel, ...]:
        return (self.plain,) if self.project is None else (self.plain, self.project)


def _encode_execution(m: hm.ActionExecution) -> tuple[IdlStruct, IdlStruct | None]:
    wrapped = bridge_action_execution_to_idl(m)
    return wrapped.execution, wrapped


def _encode_executing_plan(m: hm.ExecutingPlan | hm.Plan) -> tuple[IdlStruct, IdlStruct | None]:
    executing = m if isinstance(m, hm.ExecutingPlan) else hm.ExecutingPlan(plan=m)
    wrapped = executing_plan_to_idl(executing)
    return wrapped.plan, wrapped


def _route(
    topic: str,
    accepts: tuple[type, ...],
    plain: tuple[type[IdlStruct], Callable[[Any], object]],
    encode: Callable[[Any], tuple[IdlStruct, IdlStruct | None]],
    project: tuple[type[IdlStruct], Callable[[Any], object]] | None = None,
    depth: int = 10,
) -> Route:
    return Route(
        hub_topic=topic,
        accepts=accepts,
        plain=Channel(dds_topic_name(topic), plain[0], depth, plain[1], project=False),
        project=(
            None
            if project is None
            else Channel(
                dds_topic_name(topic, project=True), project[0], depth, project[1], project=True
            )
        ),
        encode=encode,
    )


ROUTES: dict[str, Route] = {
    r.hub_topic: r
    for r in (
        # PlanSys2 publishes and subscribes actions_hub with QoS(100).reliable().
        _route(
            hm.Topics.ACTIONS_HUB,
            (hm.ActionExecution,),
            (T.ActionExecution_, action_execution_from_idl),
            _encode_execution,
            (T.BridgeActionExecution_, bridge_action_execution_from_idl),
            depth=100,
        ),
        _route(
            hm.Topics.PERFORMERS_STATUS,
            (hm.ActionPerformerStatus,),
            (T.ActionPerformerStatus_, performer_status_from_idl),
            lambda m: (performer_status_to_idl(m), None),
            depth=100,
        ),
        _route(
            hm.Topics.ACTION_EXECUTION_INFO,
            (hm.ActionExecutionInfo,),
            (T.ActionExecutionInfo_, execution_info_from_idl),
            lambda m: (execution_info_to_idl(m), None),
            depth=100,
        ),
        _route(
            hm.Topics.EXECUTING_PLAN,
            (hm.ExecutingPlan, hm.Plan),
            (T.Plan_, lambda x: hm.ExecutingPlan(plan=plan_from_idl(x))),
            _encode_executing_plan,
            (T.BridgeExecutingPlan_, executing_plan_from_idl),
        ),
        _route(
            hm.Topics.KNOWLEDGE,
            (hm.Knowledge,),
            (T.Knowledge_, knowledge_from_idl),
            lambda m: (knowledge_to_idl(m), None),
        ),
        _route(
            hm.Topics.DOT_GRAPH,
            (hm.DotGraph,),
            (T.String_, lambda x: hm.DotGraph(text=x.data)),
            lambda m: (T.String_(data=m.text), None),
        ),
    )
}
"""Every hub topic the DDS transport carries, by hub topic name."""


def encode(hub_topic: str, msg: object) -> tuple[IdlStruct, IdlStruct | None]:
    """The plain sample (and the project wrapper, if the topic has one) for ``msg``."""
    route = ROUTES.get(hub_topic)
    if route is None:
        raise HubError(f"topic {hub_topic!r} has no DDS type (known: {', '.join(ROUTES)})")
    if not isinstance(msg, route.accepts):
        wanted = " or ".join(t.__name__ for t in route.accepts)
        raise HubError(
            f"cannot publish {type(msg).__name__} on {hub_topic!r} over DDS: expected {wanted}"
        )
    return route.encode(msg)


def decode(channel: Channel, sample: Any) -> object:
    """The hub message a sample of ``channel`` stands for (ValueError if it has none)."""
    return channel.decode(sample)
