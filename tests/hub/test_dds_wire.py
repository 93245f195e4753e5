"""The compiled XCDR1 codec writes and reads exactly what Cyclone's own serialiser does."""

from __future__ import annotations

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.auth import SIGNED_TOPIC, SignedMessage
from plansys_bridge.hub.dds_codec import ROUTES, encode, wire_sources
from plansys_bridge.hub.dds_wire import wire_codec
from plansys_bridge.interfaces.dds import dds_type

MESSAGES: list[tuple[str, object]] = [
    (
        hm.Topics.ACTIONS_HUB,
        hm.ActionExecution(
            hm.ExecutionType.RESPONSE, "p7", "move", ("r1", "a", "bé"), True, 0.5, "ok", 12.5, "x#1"
        ),
    ),
    (hm.Topics.ACTIONS_HUB, hm.ActionExecution(hm.ExecutionType.REQUEST, "", "wait")),
    (
        hm.Topics.PERFORMERS_STATUS,
        hm.ActionPerformerStatus(12.25, hm.PerformerState.RUNNING, "move", ("r1", ""), "n1"),
    ),
    (
        hm.Topics.ACTION_EXECUTION_INFO,
        hm.ActionExecutionInfo(
            hm.ActionStatus.EXECUTING, 1.5, 2.75, "(move a b)", "move", ("a", "b"), 3.0, 0.25, "m"
        ),
    ),
    (
        hm.Topics.EXECUTING_PLAN,
        hm.ExecutingPlan(
            hm.Plan((hm.PlanItem(0.0, "(a b)", 1.5), hm.PlanItem(1.0, "(c)", 2.0))), "p1"
        ),
    ),
    (hm.Topics.EXECUTING_PLAN, hm.ExecutingPlan()),
    (hm.Topics.KNOWLEDGE, hm.Knowledge(("a", "b"), ("(x a)",), (), "(and)")),
    (SIGNED_TOPIC, SignedMessage("actions_hub", "me", 7, 1.5, "{}", bytes(range(32)))),
    (SIGNED_TOPIC, SignedMessage("actions_hub", "me", 0, 0.0, "", b"")),
    (hm.Topics.DOT_GRAPH, hm.DotGraph("digraph {}")),
]


def _samples() -> list[tuple[str, object]]:
    """(ROS type, Cyclone sample) for every DDS topic of every message above."""
    found = []
    for topic, msg in MESSAGES:
        route = ROUTES[topic]
        for sample in encode(topic, msg):
            if sample is None:
                continue
            channel = next(c for c in route.channels if c.idl_type is type(sample))
            found.append((channel.ros_type, sample))
    return found


@pytest.mark.parametrize(("ros_type", "sample"), _samples())
def test_bytes_are_cyclones_and_read_back(ros_type: str, sample: object) -> None:
    codec = wire_codec(ros_type)
    theirs = sample.serialize(use_version_2=False)  # type: ignore[attr-defined]
    theirs = theirs.ljust((len(theirs) + 3) & ~3, b"\0")  # as DataWriter.write pads
    assert codec.encode(sample) == theirs
    assert codec.decode(theirs) == sample


@pytest.mark.parametrize(("topic", "msg"), MESSAGES)
def test_hub_messages_go_straight_to_the_same_bytes_and_back(topic: str, msg: object) -> None:
    route = ROUTES[topic]
    for channel, sample, source in zip(
        route.channels, encode(topic, msg), wire_sources(topic, msg), strict=False
    ):
        assert sample is not None
        theirs = sample.serialize(use_version_2=False)  # type: ignore[attr-defined]
        assert channel.write(source) == theirs.ljust((len(theirs) + 3) & ~3, b"\0")
        assert channel.read(theirs) == channel.decode(sample)


def test_unknown_constants_and_numbers_that_are_not_finite_are_refused() -> None:
    channel = ROUTES[hm.Topics.ACTIONS_HUB].plain
    cls = dds_type("plansys2_msgs/msg/ActionExecution")
    with pytest.raises(ValueError, match=r"ActionExecution\.type is 42, not one of REQUEST=1"):
        channel.read(cls(type=42).serialize(use_version_2=False))
    with pytest.raises(ValueError, match="completion is nan, not a finite number"):
        channel.read(cls(type=5, completion=float("nan")).serialize(use_version_2=False))


def test_other_representations_are_read_by_cyclone() -> None:
    ros_type = "plansys2_msgs/msg/ActionPerformerStatus"
    sample = dds_type(ros_type)(state=1, action="move", specialized_arguments=["r1"])
    xcdr2 = sample.serialize(use_version_2=True)
    assert xcdr2[:2] != b"\x00\x01"
    assert wire_codec(ros_type).decode(xcdr2) == sample


def test_malformed_bytes_are_a_value_error() -> None:
    codec = wire_codec("plansys2_msgs/msg/ActionExecution")
    good = codec.encode(dds_type("plansys2_msgs/msg/ActionExecution")(action="move"))
    for bad in (
        good[:9],  # cut inside a string length
        good[:4] + b"\x00" * 4 + b"\xff\xff\xff\x7f",  # a string running past the end
        good[:8] + b"\x05\x00\x00\x00\xff\xfe\xfd\xfc\x00" + good[17:],  # not UTF-8
    ):
        with pytest.raises(ValueError, match="ActionExecution"):
            codec.decode(bad)


def test_values_the_type_cannot_carry_are_a_value_error() -> None:
    cls = dds_type("plansys2_msgs/msg/ActionExecution")
    with pytest.raises(ValueError, match="ActionExecution"):
        wire_codec("plansys2_msgs/msg/ActionExecution").encode(cls(type=1 << 20))
