"""Hub messages <-> DDS samples, and which DDS topics carry each hub topic.

Every hub topic travels on ``rt/<topic>`` with its PlanSys2 type, so a ROS 2 node sees
the traffic it expects. The DDS types are generated from the vendored ``.msg`` texts
(:func:`plansys_bridge.interfaces.dds.dds_type`) and a hub message is converted field
by field, by name, so the only layout anywhere is upstream's text. Where this project
adds fields PlanSys2 lacks (``ActionExecution.bid`` / ``request_id``,
``ExecutingPlan.plan_id``), the complete message also goes, wrapped, on
``rt/plansys_bridge/<topic>`` with a ``plansys_bridge_msgs`` type: the same split the
bag recorder uses, so DDS traffic and recorded bags agree. A project receiver takes
such messages from the wrapper topic only and ignores the plain copy (see
:class:`~plansys_bridge.hub.dds.DdsTransport`); plain messages from other DDS nodes,
which have no wrapper, arrive with the extra fields at their defaults.
``DotGraph.plan_id`` is not carried (PlanSys2 and the bags use a ``std_msgs/String``),
and a bare :class:`~plansys_bridge.hub.messages.Plan` published on ``executing_plan``
arrives as an ``ExecutingPlan`` with no plan id.

Stamps are float seconds in the hub and ``builtin_interfaces/Time`` on the wire
(nanosecond resolution); ``completion`` and plan item times are ``float32`` as in
PlanSys2, so they come back rounded to single precision. Decoding checks what a
foreign writer could get wrong (a constant outside the ``.msg``'s, a non-finite
number): such a sample raises ``ValueError`` and the transport drops it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from cyclonedds.idl import IdlStruct

from plansys_bridge.errors import HubError
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.auth import SIGNED_TOPIC, SignedMessage
from plansys_bridge.hub.dds_convert import (
    Decoder,
    from_idl_seconds,
    hub_decoder,
    hub_encoder,
    to_idl_duration,
    to_idl_time,
)
from plansys_bridge.hub.dds_execution import execution_reader, execution_writer
from plansys_bridge.hub.dds_qos import TOPIC_QOS, TopicQos
from plansys_bridge.hub.dds_wire import hub_reader, wire_codec
from plansys_bridge.interfaces.dds import dds_type

__all__ = [
    "BRIDGE_PREFIX",
    "ROUTES",
    "Channel",
    "Route",
    "check_accepts",
    "dds_topic_name",
    "decode",
    "encode",
    "from_idl_seconds",
    "to_idl_duration",
    "to_idl_time",
    "wire_sources",
]

ROS_PREFIX = "rt/"
"""ROS 2 puts a topic ``/name`` on the DDS topic ``rt/name``."""

BRIDGE_PREFIX = "plansys_bridge/"
"""The project's wrapper topics live under this namespace (as ``/plansys_bridge`` in bags)."""

ACTION_EXECUTION = "plansys2_msgs/msg/ActionExecution"
ACTION_EXECUTION_INFO = "plansys2_msgs/msg/ActionExecutionInfo"
ACTION_PERFORMER_STATUS = "plansys2_msgs/msg/ActionPerformerStatus"
PLAN = "plansys2_msgs/msg/Plan"
KNOWLEDGE = "plansys2_msgs/msg/Knowledge"
STRING = "std_msgs/msg/String"
BRIDGE_ACTION_EXECUTION = "plansys_bridge_msgs/msg/ActionExecution"
BRIDGE_EXECUTING_PLAN = "plansys_bridge_msgs/msg/ExecutingPlan"
BRIDGE_SIGNED = "plansys_bridge_msgs/msg/Signed"


def dds_topic_name(hub_topic: str, *, project: bool = False) -> str:
    """``actions_hub`` -> ``rt/actions_hub`` (``rt/plansys_bridge/actions_hub`` if project)."""
    name = hub_topic.lstrip("/")
    return ROS_PREFIX + (BRIDGE_PREFIX if project else "") + name


# -- the messages that are not one hub dataclass per ROS type ------------------------------

_encode_bridge_execution = hub_encoder(BRIDGE_ACTION_EXECUTION)
_decode_execution_plain = hub_decoder(hm.ActionExecution, ACTION_EXECUTION)
_encode_bridge_plan = hub_encoder(BRIDGE_EXECUTING_PLAN)
_decode_plan = hub_decoder(hm.Plan, PLAN)


def _encode_execution(m: hm.ActionExecution) -> tuple[IdlStruct, IdlStruct | None]:
    wrapped = _encode_bridge_execution(hm.BridgeActionExecution.of(m))
    return wrapped.execution, wrapped


def _decode_bridge_execution(x: Any) -> hm.ActionExecution:
    m = _decode_execution_plain(x.execution)
    bid = float(x.bid) if x.has_bid else None
    return hm.ActionExecution(**{**vars(m), "request_id": x.request_id, "bid": bid})


def _encode_executing_plan(m: hm.ExecutingPlan | hm.Plan) -> tuple[IdlStruct, IdlStruct | None]:
    executing = m if isinstance(m, hm.ExecutingPlan) else hm.ExecutingPlan(plan=m)
    wrapped = _encode_bridge_plan(executing)
    return wrapped.plan, wrapped


def _decode_bridge_plan(x: Any) -> hm.ExecutingPlan:
    return hm.ExecutingPlan(plan=_decode_plan(x.plan), plan_id=x.plan_id)


def _plain(ros_type: str) -> Callable[[Any], tuple[IdlStruct, IdlStruct | None]]:
    encoder = hub_encoder(ros_type)
    return lambda m: (encoder(m), None)


# -- straight to and from bytes (hub/dds_wire.py): what the transport uses ------------------


@dataclass(frozen=True)
class _Text:
    """A ``std_msgs/String`` as the hub sees it."""

    data: str


def _merge_bridge(x: hm.BridgeActionExecution) -> hm.ActionExecution:
    """The wrapped message with the wrapper's fields (as ``dataclasses.replace`` would,
    filled in at once like every decoded message: see :mod:`~plansys_bridge.hub.dds_wire`)."""
    merged: hm.ActionExecution = object.__new__(hm.ActionExecution)
    vars(merged).update(
        vars(x.execution), request_id=x.request_id, bid=x.bid if x.has_bid else None
    )
    return merged


_HUB_FORMS: dict[str, tuple[type, Callable[[Any], Any] | None]] = {
    ACTION_EXECUTION: (hm.ActionExecution, None),
    BRIDGE_ACTION_EXECUTION: (hm.BridgeActionExecution, _merge_bridge),
    ACTION_PERFORMER_STATUS: (hm.ActionPerformerStatus, None),
    ACTION_EXECUTION_INFO: (hm.ActionExecutionInfo, None),
    PLAN: (hm.Plan, lambda plan: hm.ExecutingPlan(plan=plan)),
    BRIDGE_EXECUTING_PLAN: (hm.ExecutingPlan, None),
    KNOWLEDGE: (hm.Knowledge, None),
    BRIDGE_SIGNED: (SignedMessage, None),
    STRING: (_Text, lambda text: hm.DotGraph(text=text.data)),
}
"""Per DDS type: the hub dataclass its bytes are read into, and what then makes the
hub message of it (the same results as the ``decode`` functions of the routes)."""


def _executing_plan_sources(m: hm.ExecutingPlan | hm.Plan) -> tuple[Any, Any]:
    executing = m if isinstance(m, hm.ExecutingPlan) else hm.ExecutingPlan(plan=m)
    return executing.plan, executing


_SOURCES: dict[str, Callable[[Any], tuple[Any, Any | None]]] = {
    hm.Topics.ACTIONS_HUB: lambda m: (m, hm.BridgeActionExecution.of(m)),
    hm.Topics.EXECUTING_PLAN: _executing_plan_sources,
    hm.Topics.DOT_GRAPH: lambda m: (_Text(m.text), None),
}
"""Per hub topic, what the plain and the wrapper sample are written from (objects
with the DDS types' field names); by default the message itself, unwrapped."""


# -- routing -----------------------------------------------------------------------------


@dataclass(frozen=True)
class Channel:
    """One DDS topic: its name, ROS 2 type, QoS, and how samples become hub messages."""

    dds_topic: str
    ros_type: str
    qos: TopicQos
    decode: Decoder
    project: bool
    """True for the ``plansys_bridge_msgs`` wrapper topic of a hub topic."""

    @property
    def idl_type(self) -> type[IdlStruct]:
        return dds_type(self.ros_type)

    @cached_property
    def read(self) -> Callable[[bytes], object]:
        """The sample's bytes (with their encapsulation header) -> the hub message."""
        decoded = self.decode
        cls = self.idl_type
        if self.ros_type in (ACTION_EXECUTION, BRIDGE_ACTION_EXECUTION):
            return execution_reader(self.ros_type, lambda data: decoded(cls.deserialize(data)))
        hub, finish = _HUB_FORMS[self.ros_type]
        fast = hub_reader(self.ros_type, hub, self.decode)
        if finish is None:
            return fast

        def read(data: bytes) -> object:
            if data[:2] != b"\x00\x01":
                return decoded(cls.deserialize(data))
            return finish(fast(data))

        return read

    @cached_property
    def write(self) -> Callable[[Any], bytes]:
        """An object with the type's field names -> the sample's XCDR1 bytes."""
        return wire_codec(self.ros_type).encode

    @property
    def depth(self) -> int:
        return self.qos.depth


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

    @cached_property
    def to_bytes(self) -> tuple[Callable[[Any], bytes], Callable[[Any], bytes] | None]:
        """hub message -> the bytes of its plain sample, and of its wrapper sample if
        the topic has one (what :attr:`Channel.write` makes of :func:`wire_sources`)."""
        if self.hub_topic == hm.Topics.ACTIONS_HUB:
            return execution_writer(ACTION_EXECUTION), execution_writer(BRIDGE_ACTION_EXECUTION)
        split = _SOURCES.get(self.hub_topic)
        plain = self.plain.write
        if split is None:
            return plain, None
        project = self.project.write if self.project is not None else None
        return (
            lambda m: plain(split(m)[0]),
            None if project is None else lambda m: project(split(m)[1]),
        )


def _route(
    topic: str,
    accepts: tuple[type, ...],
    plain: tuple[str, Decoder],
    encode: Callable[[Any], tuple[IdlStruct, IdlStruct | None]],
    project: tuple[str, Decoder] | None = None,
) -> Route:
    qos = TOPIC_QOS[topic]
    return Route(
        hub_topic=topic,
        accepts=accepts,
        plain=Channel(dds_topic_name(topic), plain[0], qos, plain[1], project=False),
        project=(
            None
            if project is None
            else Channel(dds_topic_name(topic, project=True), project[0], qos, project[1], True)
        ),
        encode=encode,
    )


ROUTES: dict[str, Route] = {
    r.hub_topic: r
    for r in (
        _route(
            hm.Topics.ACTIONS_HUB,
            (hm.ActionExecution,),
            (ACTION_EXECUTION, _decode_execution_plain),
            _encode_execution,
            (BRIDGE_ACTION_EXECUTION, _decode_bridge_execution),
        ),
        _route(
            hm.Topics.PERFORMERS_STATUS,
            (hm.ActionPerformerStatus,),
            (
                ACTION_PERFORMER_STATUS,
                hub_decoder(hm.ActionPerformerStatus, ACTION_PERFORMER_STATUS),
            ),
            _plain(ACTION_PERFORMER_STATUS),
        ),
        _route(
            hm.Topics.ACTION_EXECUTION_INFO,
            (hm.ActionExecutionInfo,),
            (ACTION_EXECUTION_INFO, hub_decoder(hm.ActionExecutionInfo, ACTION_EXECUTION_INFO)),
            _plain(ACTION_EXECUTION_INFO),
        ),
        _route(
            hm.Topics.EXECUTING_PLAN,
            (hm.ExecutingPlan, hm.Plan),
            (PLAN, lambda x: hm.ExecutingPlan(plan=_decode_plan(x))),
            _encode_executing_plan,
            (BRIDGE_EXECUTING_PLAN, _decode_bridge_plan),
        ),
        _route(
            hm.Topics.KNOWLEDGE,
            (hm.Knowledge,),
            (KNOWLEDGE, hub_decoder(hm.Knowledge, KNOWLEDGE)),
            _plain(KNOWLEDGE),
        ),
        _route(
            SIGNED_TOPIC,
            (SignedMessage,),
            (
                BRIDGE_SIGNED,
                lambda x: SignedMessage(
                    x.topic, x.sender, int(x.counter), float(x.stamp), x.payload, bytes(x.mac)
                ),
            ),
            lambda m: (
                dds_type(BRIDGE_SIGNED)(
                    topic=m.topic,
                    sender=m.sender,
                    counter=m.counter,
                    stamp=m.stamp,
                    payload=m.payload,
                    mac=list(m.mac),
                ),
                None,
            ),
        ),
        _route(
            hm.Topics.DOT_GRAPH,
            (hm.DotGraph,),
            (STRING, lambda x: hm.DotGraph(text=x.data)),
            lambda m: (dds_type(STRING)(data=m.text), None),
        ),
    )
}
"""Every hub topic the DDS transport carries, by hub topic name."""


def encode(hub_topic: str, msg: object) -> tuple[IdlStruct, IdlStruct | None]:
    """The plain sample (and the project wrapper, if the topic has one) for ``msg``."""
    return _accepting(hub_topic, msg).encode(msg)


def wire_sources(hub_topic: str, msg: object) -> tuple[Any, Any | None]:
    """What :attr:`Channel.write` turns into the plain and the wrapper sample of ``msg``."""
    _accepting(hub_topic, msg)
    split = _SOURCES.get(hub_topic)
    return split(msg) if split is not None else (msg, None)


def _accepting(hub_topic: str, msg: object) -> Route:
    route = ROUTES.get(hub_topic)
    if route is None:
        raise HubError(f"topic {hub_topic!r} has no DDS type (known: {', '.join(ROUTES)})")
    check_accepts(route, msg)
    return route


def check_accepts(route: Route, msg: object) -> None:
    """HubError unless ``route`` carries messages of ``msg``'s type."""
    if not isinstance(msg, route.accepts):
        wanted = " or ".join(t.__name__ for t in route.accepts)
        raise HubError(
            f"cannot publish {type(msg).__name__} on {route.hub_topic!r} over DDS: "
            f"expected {wanted}"
        )


def decode(channel: Channel, sample: Any) -> object:
    """The hub message a sample of ``channel`` stands for (ValueError if it has none)."""
    return channel.decode(sample)
