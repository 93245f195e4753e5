"""PlanSys2's ``get_domain_action_details``, called by an independent ROS 2 client.

The client's types are typed here from the upstream texts (ros2_planning_system,
rolling): plansys2_msgs/srv/GetDomainActionDetails.srv, msg/Action.msg and msg/Tree.msg;
Param and Node come from ros2_upstream.py. Framing as in test_problem_expert_services.py.
"""

import asyncio
import random
from dataclasses import dataclass, field

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int64, sequence, uint64
from ros2_upstream import Node_, Param_, RawClient

from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.ros2.domain_planner_services import serve_domain_expert
from plansys_bridge.ros2.node import Ros2Node

pytestmark = [pytest.mark.timeout(60), pytest.mark.usefixtures("no_leaks")]

DOMAIN = """
(define (domain charging)
  (:requirements :strips :typing :fluents)
  (:types robot dock)
  (:predicates (docked ?r - robot ?d - dock) (free ?d - dock))
  (:functions (battery ?r - robot))
  (:action dock
    :parameters (?r - robot ?d - dock)
    :precondition (and (free ?d) (< (battery ?r) 20))
    :effect (and (docked ?r ?d) (not (free ?d)) (increase (battery ?r) 80))))
"""

# plansys2_msgs/msg/Node.msg constants
AND, NOT, PREDICATE, FUNCTION, EXPRESSION, FUNCTION_MODIFIER, NUMBER = 1, 3, 5, 6, 7, 8, 9
COMP_LT, INCREASE = 17, 23


@dataclass
class Tree_(IdlStruct, typename="plansys2_msgs::msg::dds_::Tree_"):
    nodes: sequence[Node_] = field(default_factory=list)


@dataclass
class Action_(IdlStruct, typename="plansys2_msgs::msg::dds_::Action_"):
    name: str = ""
    parameters: sequence[Param_] = field(default_factory=list)
    preconditions: Tree_ = field(default_factory=Tree_)
    effects: Tree_ = field(default_factory=Tree_)


@dataclass
class GetDomainActionDetails_Request_(
    IdlStruct, typename="plansys2_msgs::srv::dds_::GetDomainActionDetails_Request_"
):
    guid: uint64 = 0
    seq: int64 = 0
    action: str = ""
    parameters: sequence[str] = field(default_factory=list)


@dataclass
class GetDomainActionDetails_Response_(
    IdlStruct, typename="plansys2_msgs::srv::dds_::GetDomainActionDetails_Response_"
):
    guid: uint64 = 0
    seq: int64 = 0
    action: Action_ = field(default_factory=Action_)
    success: bool = False
    error_info: str = ""


def shape(tree: Tree_) -> list[tuple[int, int, int, str, list[str], list[int]]]:
    return [
        (
            n.node_type,
            n.expression_type,
            n.modifier_type,
            n.name,
            [p.name for p in n.parameters],
            list(n.children),
        )
        for n in tree.nodes
    ]


def test_get_domain_action_details_gives_parameters_and_trees() -> None:
    async def main() -> None:
        domain = random.SystemRandom().randint(1, 232)
        node = Ros2Node(domain, name="domain_expert")
        await node.start()
        services = serve_domain_expert(node, DomainExpert.from_text(DOMAIN))
        dp = DomainParticipant(domain)
        try:
            client = RawClient(
                dp,
                "/domain_expert/get_domain_action_details",
                GetDomainActionDetails_Request_,
                GetDomainActionDetails_Response_,
            )
            reply = await client.call(action="dock")
            assert reply.success, reply.error_info
            action = reply.action
            assert action.name == "dock"
            assert [(p.name, p.type) for p in action.parameters] == [
                ("?0", "robot"),
                ("?1", "dock"),
            ]
            assert shape(action.preconditions) == [
                (AND, 0, 0, "", [], [1, 2]),
                (PREDICATE, 0, 0, "free", ["?1"], []),
                (EXPRESSION, COMP_LT, 0, "", [], [3, 4]),
                (FUNCTION, 0, 0, "battery", ["?0"], []),
                (NUMBER, 0, 0, "", [], []),
            ]
            assert action.preconditions.nodes[4].value == 20.0
            assert shape(action.effects) == [
                (AND, 0, 0, "", [], [1, 2, 4]),
                (PREDICATE, 0, 0, "docked", ["?0", "?1"], []),
                (NOT, 0, 0, "", [], [3]),
                (PREDICATE, 0, 0, "free", ["?1"], []),
                (FUNCTION_MODIFIER, 0, INCREASE, "", [], [5, 6]),
                (FUNCTION, 0, 0, "battery", ["?0"], []),
                (NUMBER, 0, 0, "", [], []),
            ]

            # With objects, as PlanSys2 grounds an action for its executor.
            reply = await client.call(action="dock", parameters=["r1", "d2"])
            assert [p.name for p in reply.action.parameters] == ["r1", "d2"]
            assert shape(reply.action.effects)[1][4] == ["r1", "d2"]

            reply = await client.call(action="fly")
            assert not reply.success
            assert "fly" in reply.error_info
        finally:
            dp.__del__()
            await services.close()
            await node.close()

    asyncio.run(main())
