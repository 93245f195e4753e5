"""PlanSys2's problem expert services, called by an independent ROS 2 service client.

The client below is a plain Cyclone DDS program. Its types are typed in the tests from
the upstream texts, not taken from the project: plansys2_msgs/srv/GetProblemInstances.srv
and AffectNode.srv here (ros2_planning_system, rolling), the messages in
ros2_upstream.py. The request/reply framing is rmw_cyclonedds' (rmw_node.cpp:
``cdds_request_header_t {uint64_t guid; int64_t seq;}`` before the message, topics
``rq/<service>Request`` / ``rr/<service>Reply``, the client's writer handle as guid).
"""

import asyncio
import random
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int64, sequence, uint64
from ros2_upstream import PREDICATE, Empty_, Node_, Param_, RawClient

from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.ros2.node import Ros2Node
from plansys_bridge.ros2.problem_expert_services import serve_problem_expert

pytestmark = [pytest.mark.timeout(60), pytest.mark.usefixtures("no_leaks")]

DOMAIN = Path(__file__).resolve().parents[2] / "configs" / "pddl" / "flat_navigation.pddl"


# -- the services' own types, typed from GetProblemInstances.srv and AffectNode.srv ----
@dataclass
class GetProblemInstances_Request_(
    IdlStruct, typename="plansys2_msgs::srv::dds_::GetProblemInstances_Request_"
):
    guid: uint64 = 0
    seq: int64 = 0
    request: Empty_ = field(default_factory=Empty_)


@dataclass
class GetProblemInstances_Response_(
    IdlStruct, typename="plansys2_msgs::srv::dds_::GetProblemInstances_Response_"
):
    guid: uint64 = 0
    seq: int64 = 0
    success: bool = False
    instances: sequence[Param_] = field(default_factory=list)
    error_info: str = ""


@dataclass
class AffectNode_Request_(IdlStruct, typename="plansys2_msgs::srv::dds_::AffectNode_Request_"):
    guid: uint64 = 0
    seq: int64 = 0
    node: Node_ = field(default_factory=Node_)


@dataclass
class AffectNode_Response_(IdlStruct, typename="plansys2_msgs::srv::dds_::AffectNode_Response_"):
    guid: uint64 = 0
    seq: int64 = 0
    success: bool = False
    error_info: str = ""


def knowledge() -> ProblemExpert:
    k = ProblemExpert(parse_domain_files([DOMAIN]))
    k.add_instance("r1", "robot")
    k.add_instance("hall", "room")
    k.add_instance("kitchen", "room")
    k.add_predicate("(robot_at r1 hall)")
    return k


def run_with_server(body: Any) -> Any:
    async def main() -> Any:
        domain = random.SystemRandom().randint(1, 232)
        node = Ros2Node(domain, name="problem_expert")
        await node.start()
        kb = knowledge()
        services = serve_problem_expert(node, kb)
        dp = DomainParticipant(domain)
        try:
            return await body(dp, kb)
        finally:
            dp.__del__()
            await services.close()
            await node.close()

    return asyncio.run(main())


def test_get_problem_instances_and_add_problem_predicate_change_the_knowledge() -> None:
    async def body(dp: Any, kb: ProblemExpert) -> None:
        get = RawClient(
            dp,
            "/problem_expert/get_problem_instances",
            GetProblemInstances_Request_,
            GetProblemInstances_Response_,
        )
        reply = await get.call()
        assert reply.success
        assert {(p.name, p.type) for p in reply.instances} == {
            ("r1", "robot"),
            ("hall", "room"),
            ("kitchen", "room"),
        }

        add = RawClient(
            dp, "/problem_expert/add_problem_predicate", AffectNode_Request_, AffectNode_Response_
        )
        fact = Node_(
            node_type=PREDICATE,
            name="connected",
            parameters=[Param_(name="hall"), Param_(name="kitchen")],
        )
        reply = await add.call(node=fact)
        assert reply.success, reply.error_info
        assert kb.exist_predicate("(connected hall kitchen)")

        # Refused: an unknown object. The knowledge stays as it was, the reason is given.
        bad = Node_(
            node_type=PREDICATE, name="robot_at", parameters=[Param_(name="r9"), Param_("hall")]
        )
        before = kb.get_predicates()
        reply = await add.call(node=bad)
        assert not reply.success
        assert "r9" in reply.error_info
        assert kb.get_predicates() == before

    run_with_server(body)


def test_replies_go_only_to_the_calling_client() -> None:
    async def body(dp: Any, kb: ProblemExpert) -> None:
        service = "/problem_expert/get_problem_instances"
        a = RawClient(dp, service, GetProblemInstances_Request_, GetProblemInstances_Response_)
        b = RawClient(dp, service, GetProblemInstances_Request_, GetProblemInstances_Response_)
        ra, rb = await asyncio.gather(a.call(), b.call())
        assert (ra.guid, rb.guid) == (a.guid, b.guid)
        assert a.guid != b.guid

    run_with_server(body)
