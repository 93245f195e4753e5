"""Hub messages <-> DDS types: round trips, ROS 2 names, and bytes equal to the bags' CDR."""

from __future__ import annotations

import math
import struct
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.errors import HubError
from plansys_bridge.hub import dds_codec as C
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.hub import Hub
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.monitoring.recorder import MissionRecorder

# CDR strings end with NUL, so a DDS string cannot hold one (as in ROS 2).
texts = st.text(st.characters(blacklist_characters="\x00", codec="utf-8"), max_size=12)
words = st.lists(texts, max_size=4).map(tuple)
f32 = st.floats(width=32, allow_nan=False, allow_infinity=False)
# Stamps: any float second with a representable nanosecond split in int32 seconds.
stamps = st.floats(min_value=-(2.0**31) + 1, max_value=2.0**31 - 2, allow_nan=False)
bids = st.none() | st.floats(allow_nan=False, allow_infinity=False)

executions = st.builds(
    hm.ActionExecution,
    type=st.sampled_from(hm.ExecutionType),
    node_id=texts,
    action=texts,
    arguments=words,
    success=st.booleans(),
    completion=f32,
    status=texts,
    bid=bids,
    request_id=texts,
)
infos = st.builds(
    hm.ActionExecutionInfo,
    status=st.sampled_from(hm.ActionStatus),
    start_stamp=stamps,
    status_stamp=stamps,
    action_full_name=texts,
    action=texts,
    arguments=words,
    duration=stamps,
    completion=f32,
    message_status=texts,
)
statuses = st.builds(
    hm.ActionPerformerStatus,
    status_stamp=stamps,
    state=st.sampled_from(hm.PerformerState),
    action=texts,
    specialized_arguments=words,
    node_name=texts,
)
plans = st.builds(
    hm.Plan,
    items=st.lists(st.builds(hm.PlanItem, time=f32, action=texts, duration=f32), max_size=4).map(
        tuple
    ),
)
knowledge = st.builds(hm.Knowledge, instances=words, predicates=words, functions=words, goal=texts)


def through_wire(topic: str, msg: object, *, project: bool = True) -> object:
    """Encode, serialise to bytes, deserialise, decode: what a receiver gets."""
    route = C.ROUTES[topic]
    plain, wrapped = C.encode(topic, msg)
    channel, sample = (
        (route.project, wrapped) if project and route.project is not None else (route.plain, plain)
    )
    assert sample is not None
    data = sample.serialize()
    assert data[:4] == b"\x00\x01\x00\x00"  # XCDR1 (CDR_LE) header, as ROS 2 writes
    got = C.decode(channel, channel.idl_type.deserialize(data))
    # The transport's own path, straight between hub messages and bytes, agrees.
    sources = C.wire_sources(topic, msg)
    source = sources[1] if channel.project else sources[0]
    wire = channel.write(source)
    assert wire == data.ljust((len(data) + 3) & ~3, b"\0")
    assert channel.read(wire) == got
    return got


def close_seconds(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=1e-15, abs_tol=1e-9)


@settings(max_examples=150, deadline=None)
@given(executions)
def test_action_execution_round_trip_keeps_every_field(msg: hm.ActionExecution) -> None:
    assert through_wire(hm.Topics.ACTIONS_HUB, msg) == msg


@settings(max_examples=60, deadline=None)
@given(executions)
def test_plain_action_execution_drops_only_the_project_fields(msg: hm.ActionExecution) -> None:
    got = through_wire(hm.Topics.ACTIONS_HUB, msg, project=False)
    assert got == hm.ActionExecution(
        msg.type,
        msg.node_id,
        msg.action,
        msg.arguments,
        msg.success,
        msg.completion,
        msg.status,
    )


@settings(max_examples=100, deadline=None)
@given(infos)
def test_execution_info_round_trip(msg: hm.ActionExecutionInfo) -> None:
    got = through_wire(hm.Topics.ACTION_EXECUTION_INFO, msg)
    assert isinstance(got, hm.ActionExecutionInfo)
    for name in ("start_stamp", "status_stamp", "duration"):
        assert close_seconds(getattr(got, name), getattr(msg, name)), name
    exact = {"start_stamp": 0.0, "status_stamp": 0.0, "duration": 0.0}
    assert hm.ActionExecutionInfo(**{**vars(got), **exact}) == hm.ActionExecutionInfo(
        **{**vars(msg), **exact}
    )


@settings(max_examples=100, deadline=None)
@given(statuses)
def test_performer_status_round_trip(msg: hm.ActionPerformerStatus) -> None:
    got = through_wire(hm.Topics.PERFORMERS_STATUS, msg)
    assert isinstance(got, hm.ActionPerformerStatus)
    assert close_seconds(got.status_stamp, msg.status_stamp)
    assert got == hm.ActionPerformerStatus(**{**vars(msg), "status_stamp": got.status_stamp})


@settings(max_examples=60, deadline=None)
@given(plans, texts)
def test_executing_plan_round_trip(plan: hm.Plan, plan_id: str) -> None:
    msg = hm.ExecutingPlan(plan=plan, plan_id=plan_id)
    assert through_wire(hm.Topics.EXECUTING_PLAN, msg) == msg
    # A PlanSys2 node's bare Plan arrives without an id; so does a bare hub Plan.
    assert through_wire(hm.Topics.EXECUTING_PLAN, msg, project=False) == hm.ExecutingPlan(plan)
    assert through_wire(hm.Topics.EXECUTING_PLAN, plan) == hm.ExecutingPlan(plan)


@settings(max_examples=60, deadline=None)
@given(knowledge, texts)
def test_knowledge_and_dot_graph_round_trip(k: hm.Knowledge, text: str) -> None:
    assert through_wire(hm.Topics.KNOWLEDGE, k) == k
    # As in PlanSys2 and in recorded bags the graph is a std_msgs/String: no plan id.
    assert through_wire(hm.Topics.DOT_GRAPH, hm.DotGraph(text, "p1")) == hm.DotGraph(text)


@given(stamps)
def test_stamps_split_into_sec_and_nanosec(seconds: float) -> None:
    t = C.to_idl_time(seconds)
    assert 0 <= t.nanosec < 1_000_000_000
    assert close_seconds(C.from_idl_seconds(t), seconds)


def test_float32_fields_are_single_precision_like_plansys2() -> None:
    msg = hm.ActionExecution(hm.ExecutionType.FEEDBACK, "n", "move", completion=0.1)
    got = through_wire(hm.Topics.ACTIONS_HUB, msg)
    assert isinstance(got, hm.ActionExecution)
    assert got.completion == struct.unpack("<f", struct.pack("<f", 0.1))[0] != 0.1


def test_ros2_type_and_topic_names() -> None:
    assert (
        dds_type("plansys2_msgs/msg/ActionExecution").__idl_typename__
        == "plansys2_msgs::msg::dds_::ActionExecution_"
    )
    assert dds_type("builtin_interfaces/msg/Time").__idl_typename__ == (
        "builtin_interfaces::msg::dds_::Time_"
    )
    assert (
        dds_type("plansys_bridge_msgs/msg/ActionExecution").__idl_typename__
        == "plansys_bridge_msgs::msg::dds_::ActionExecution_"
    )
    hub = C.ROUTES[hm.Topics.ACTIONS_HUB]
    assert (hub.plain.dds_topic, hub.plain.depth) == ("rt/actions_hub", 100)
    assert hub.project is not None
    assert hub.project.dds_topic == "rt/plansys_bridge/actions_hub"
    assert C.ROUTES[hm.Topics.KNOWLEDGE].plain.dds_topic == "rt/problem_expert/knowledge"
    assert set(C.ROUTES) == {
        v for k, v in vars(hm.Topics).items() if k.isupper() and isinstance(v, str)
    }


def test_encode_refuses_unknown_topics_wrong_types_and_bad_stamps() -> None:
    with pytest.raises(HubError, match="'nowhere' has no DDS type"):
        C.encode("nowhere", hm.Knowledge())
    with pytest.raises(HubError, match="cannot publish Knowledge on 'actions_hub'"):
        C.encode(hm.Topics.ACTIONS_HUB, hm.Knowledge())
    with pytest.raises(HubError, match="does not fit builtin_interfaces"):
        C.to_idl_time(2.0**40)
    with pytest.raises(HubError, match="not a finite"):
        C.to_idl_duration(math.nan)


def test_decode_refuses_unknown_constants() -> None:
    channel = C.ROUTES[hm.Topics.ACTIONS_HUB].plain
    with pytest.raises(ValueError):
        C.decode(channel, dds_type("plansys2_msgs/msg/ActionExecution")(type=42))


SAMPLES: list[tuple[str, Any]] = [
    (
        hm.Topics.ACTIONS_HUB,
        hm.ActionExecution(
            hm.ExecutionType.FEEDBACK, "r1", "move", ("r1", "a"), True, 0.5, "ok", 2.5, "p:1"
        ),
    ),
    (hm.Topics.ACTIONS_HUB, hm.ActionExecution(hm.ExecutionType.REQUEST, "", "cook")),
    (
        hm.Topics.ACTION_EXECUTION_INFO,
        hm.ActionExecutionInfo(
            hm.ActionStatus.EXECUTING, 1.25, 1790000000.5, "(move r1 a)", "move", ("r1",), 3.5
        ),
    ),
    (
        hm.Topics.PERFORMERS_STATUS,
        hm.ActionPerformerStatus(1.5, hm.PerformerState.RUNNING, "move", ("r1", ""), "r1"),
    ),
    (
        hm.Topics.EXECUTING_PLAN,
        hm.ExecutingPlan(hm.Plan((hm.PlanItem(0.0, "(move r1 a b)", 3.8),)), "plan-7"),
    ),
    (hm.Topics.KNOWLEDGE, hm.Knowledge(("r1",), ("(robot_at r1 a)",), (), "(and)")),
    (hm.Topics.DOT_GRAPH, hm.DotGraph("digraph {}", "plan-7")),
]


@pytest.mark.parametrize(("topic", "msg"), SAMPLES)
def test_dds_bytes_equal_the_cdr_of_recorded_bags(topic: str, msg: Any, tmp_path: Path) -> None:
    """What goes on the wire is byte for byte what rosbags (and ROS 2) serialise."""
    recorder = MissionRecorder(Hub(), tmp_path / "unused")
    ros_messages = recorder.convert(msg)
    samples = [s for s in C.encode(topic, msg) if s is not None]
    assert len(samples) == len(ros_messages)
    for (_prefix, msgtype, ros), sample in zip(ros_messages, samples, strict=True):
        assert bytes(sample.serialize()) == bytes(recorder.store.serialize_cdr(ros, msgtype))
