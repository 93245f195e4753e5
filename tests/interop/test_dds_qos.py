"""The project's DDS writers carry PlanSys2's QoS per topic, as seen by another DDS node
through discovery, latched topics reach a late joiner, and ``ros_discovery_info`` tells
ROS 2 tools which node owns which endpoints."""

from __future__ import annotations

import asyncio
import random
import time
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from plansys2_peer import Knowledge_, Plan_
from rmw_types import ParticipantEntitiesInfo_

from plansys_bridge.clock import WallClock
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds import DdsTransport
from plansys_bridge.hub.hub import Hub

pytestmark = pytest.mark.timeout(60)

# PlanSys2 2.0.12 (rclcpp::QoS(N): keep last N, reliable, volatile):
#   ActionExecutor.cpp / ActionExecutorClient.cpp:
#     create_publisher<ActionExecution>("actions_hub", rclcpp::QoS(100).reliable())
#   ActionExecutorClient.cpp:
#     create_publisher<ActionPerformerStatus>("performers_status", rclcpp::QoS(100).reliable())
#   ExecutorNode.cpp:
#     create_publisher<std_msgs::msg::String>("dot_graph", 1)
#     create_publisher<ActionExecutionInfo>("action_execution_info", 100)
#     create_publisher<Plan>("executing_plan", rclcpp::QoS(100).transient_local())
#   ProblemExpertNode.cpp:
#     create_publisher<Knowledge>("problem_expert/knowledge", rclcpp::QoS(100).transient_local())
UPSTREAM = {
    "rt/actions_hub": (100, "volatile"),
    "rt/performers_status": (100, "volatile"),
    "rt/dot_graph": (1, "volatile"),
    "rt/action_execution_info": (100, "volatile"),
    "rt/executing_plan": (100, "transient_local"),
    "rt/problem_expert/knowledge": (100, "transient_local"),
}
DURABILITY = {
    "volatile": Policy.Durability.Volatile,
    "transient_local": Policy.Durability.TransientLocal,
}


def _publications(participant: Any, deadline: float) -> dict[str, Any]:
    """DDS topic -> the first writer discovered on it (a DCPSPublication sample)."""
    reader = BuiltinDataReader(participant, BuiltinTopicDcpsPublication)
    found: dict[str, Any] = {}
    while time.monotonic() < deadline and not set(UPSTREAM) <= set(found):
        for sample in reader.take(N=200):
            found.setdefault(sample.topic_name, sample)
        time.sleep(0.02)
    return found


def test_writer_qos_per_topic_is_upstreams() -> None:
    domain_id = random.SystemRandom().randint(1, 232)

    async def main() -> dict[str, Any]:
        hub = Hub(DdsTransport(domain_id), WallClock())
        await hub.start()
        observer = DomainParticipant(domain_id)
        try:
            return await asyncio.to_thread(_publications, observer, time.monotonic() + 10)
        finally:
            observer.__del__()
            await hub.close()

    found = asyncio.run(main())
    for topic, (depth, durability) in UPSTREAM.items():
        qos = found[topic].qos
        assert qos[Policy.History] == Policy.History.KeepLast(depth), topic
        assert qos[Policy.Durability] == DURABILITY[durability], topic
        assert isinstance(qos[Policy.Reliability], Policy.Reliability.Reliable), topic


def test_a_late_joiner_gets_the_executing_plan_and_the_knowledge() -> None:
    domain_id = random.SystemRandom().randint(1, 232)
    plan = hm.Plan((hm.PlanItem(0.0, "(move r1 hall kitchen)", 4.0),))
    knowledge = hm.Knowledge(("r1",), ("(robot_at r1 hall)",), (), "(and (visited r1 kitchen))")

    async def main() -> tuple[list[Any], list[Any]]:
        hub = Hub(DdsTransport(domain_id), WallClock())
        await hub.start()
        hub.publish(hm.Topics.EXECUTING_PLAN, hm.ExecutingPlan(plan, "p1"))
        hub.publish(hm.Topics.KNOWLEDGE, knowledge)
        await asyncio.sleep(0.2)  # published before anybody else is there
        late = DomainParticipant(domain_id)
        latched = Qos(
            Policy.Reliability.Reliable(duration(seconds=1)),
            Policy.History.KeepLast(100),
            Policy.Durability.TransientLocal,
        )
        try:
            plans = DataReader(late, Topic(late, "rt/executing_plan", Plan_), latched)
            known = DataReader(
                late, Topic(late, "rt/problem_expert/knowledge", Knowledge_), latched
            )
            got_plans: list[Any] = []
            got_knowledge: list[Any] = []
            deadline = time.monotonic() + 10
            while not (got_plans and got_knowledge) and time.monotonic() < deadline:
                got_plans += plans.take(N=10)
                got_knowledge += known.take(N=10)
                await asyncio.sleep(0.02)
            return got_plans, got_knowledge
        finally:
            late.__del__()
            await hub.close()

    plans, knowledges = asyncio.run(main())
    assert [[i.action for i in p.items] for p in plans] == [["(move r1 hall kitchen)"]]
    assert [k.goal for k in knowledges] == ["(and (visited r1 kitchen))"]
    assert knowledges[0].predicates == ["(robot_at r1 hall)"]


def test_ros_discovery_info_names_the_node_and_its_endpoints() -> None:
    """What ``ros2 node list`` reads: the node with the GUIDs of its readers and writers."""
    domain_id = random.SystemRandom().randint(1, 232)

    async def main() -> tuple[list[Any], dict[str, Any]]:
        hub = Hub(DdsTransport(domain_id, node_name="dds_flat_executor"), WallClock())
        await hub.start()
        tool = DomainParticipant(domain_id)
        try:
            reader = DataReader(
                tool,
                Topic(tool, "ros_discovery_info", ParticipantEntitiesInfo_),
                Qos(
                    Policy.Reliability.Reliable(duration(seconds=1)),
                    Policy.Durability.TransientLocal,
                    Policy.History.KeepLast(1),
                ),
            )
            infos: list[Any] = []
            deadline = time.monotonic() + 10
            while not infos and time.monotonic() < deadline:
                infos += reader.take(N=10)
                await asyncio.sleep(0.02)
            publications = await asyncio.to_thread(_publications, tool, deadline)
            return infos, publications
        finally:
            tool.__del__()
            await hub.close()

    infos, publications = asyncio.run(main())
    assert len(infos) == 1
    (node,) = infos[0].node_entities_info_seq
    assert (node.node_namespace, node.node_name) == ("/", "dds_flat_executor")
    writers = {bytes(g.data) for g in node.writer_gid_seq}
    assert publications["rt/actions_hub"].key.bytes in writers
    assert publications["rt/actions_hub"].participant_key.bytes == bytes(infos[0].gid.data)
    assert len(node.reader_gid_seq) == len(node.writer_gid_seq) >= len(UPSTREAM)
