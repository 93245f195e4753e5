"""PlanSys2's problem expert services on DDS, answered from a live ProblemExpert.

Names and types are those PlanSys2 creates (plansys2_problem_expert,
``src/plansys2_problem_expert/ProblemExpertNode.cpp``, branch rolling): the node
``problem_expert`` serves ``/problem_expert/add_problem`` (AddProblem),
``add_problem_goal`` (AddProblemGoal), ``add_problem_instance`` /
``remove_problem_instance`` (AffectParam), ``add_problem_predicate`` /
``remove_problem_predicate`` / ``add_problem_function`` / ``remove_problem_function`` /
``update_problem_function`` (AffectNode), ``get_problem_goal`` (GetProblemGoal),
``get_problem_instance`` (GetProblemInstanceDetails), ``get_problem_instances``
(GetProblemInstances), ``get_problem_predicate`` / ``get_problem_function``
(GetNodeDetails), ``get_problem_predicates`` / ``get_problem_functions`` (GetStates),
``get_problem`` (GetProblem), ``is_problem_goal_satisfied`` (IsProblemGoalSatisfied),
``remove_problem_goal`` (RemoveProblemGoal), ``clear_problem_knowledge``
(ClearProblemKnowledge) and ``exist_problem_predicate`` / ``exist_problem_function``
(ExistNode).

As upstream, a request the knowledge refuses is answered with ``success: false`` and
the reason in ``error_info`` (here the knowledge base's own message, naming what is
wrong); the knowledge is left as it was. Every accepted change reaches the hub's
``problem_expert/knowledge`` topic through the knowledge's subscribers, as any other
change does.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import FluentRef, FluentValue
from plansys_bridge.ros2.node import Ros2Node
from plansys_bridge.ros2.services import ServiceServer
from plansys_bridge.ros2.trees import (
    atom_node,
    condition_tree,
    fluent_node,
    node_text,
    param,
    tree_text,
)

__all__ = ["ServiceSet", "serve_problem_expert"]

log = logging.getLogger(__name__)

Answer = Callable[[Any], dict[str, Any]]
"""Turns a request into the response's fields; raising PlansysBridgeError means refused."""


@dataclass
class ServiceSet:
    """Servers of one node; ``close()`` removes them all."""

    servers: list[ServiceServer]

    @property
    def names(self) -> list[str]:
        return [s.service for s in self.servers]

    async def close(self) -> None:
        for server in self.servers:
            await server.close()


def serve_table(node: Ros2Node, prefix: str, table: dict[str, tuple[str, Answer]]) -> ServiceSet:
    """Serve ``{name: (srv type, answer)}`` under ``/<prefix>/<name>``.

    An answer that raises a project error gives ``success: false`` with the message in
    ``error_info`` (for services whose response has those fields), as PlanSys2 does.
    """
    servers = []
    for name, (srv_type, answer) in table.items():
        servers.append(
            ServiceServer(
                node, f"{prefix}/{name}", srv_type, _handler(f"/{prefix}/{name}", srv_type, answer)
            )
        )
    return ServiceSet(servers)


def _handler(service: str, srv_type: str, answer: Answer) -> Callable[[Any], Any]:
    response_type = dds_type(f"{srv_type}_Response")
    has_error = "error_info" in getattr(response_type, "__annotations__", {})

    def handle(request: Any) -> Any:
        try:
            return response_type(**answer(request))
        except PlansysBridgeError as exc:
            log.info("%s refused: %s", service, exc)
            if not has_error:
                return response_type()
            return response_type(success=False, error_info=str(exc))

    return handle


def serve_problem_expert(node: Ros2Node, knowledge: ProblemExpert) -> ServiceSet:
    """Serve every problem expert service of PlanSys2 from ``knowledge``."""
    k = knowledge
    affect_node = "plansys2_msgs/srv/AffectNode"
    get_states = "plansys2_msgs/srv/GetStates"
    details = "plansys2_msgs/srv/GetNodeDetails"
    exist = "plansys2_msgs/srv/ExistNode"

    def ok(**fields: Any) -> dict[str, Any]:
        return {"success": True, **fields}

    def changed(done: bool, what: str) -> dict[str, Any]:
        # PlanSys2 answers success=false for a change that changes nothing
        # (an existing fact added again is "not valid" there).
        return ok() if done else {"success": False, "error_info": what}

    def instance(name: str) -> dict[str, Any]:
        typ = k.get_instance(name)
        if typ is None:
            return {"success": False, "error_info": "Instance not found"}
        return ok(instance=param(name.lower(), typ))

    def predicate(request: Any) -> dict[str, Any]:
        atom = k.get_predicate(request.expression)
        if atom is None:
            return {"success": False, "error_info": "Predicate not found"}
        return ok(node=atom_node(atom))

    def function(request: Any) -> dict[str, Any]:
        text = request.expression
        value = k.get_function(text)
        if value is None:
            return {"success": False, "error_info": "Function not found"}
        words = text.replace("(", " ").replace(")", " ").split()
        ref = FluentRef(words[0].lower(), tuple(w.lower() for w in words[1:]))
        return ok(node=fluent_node(FluentValue(ref, value)))

    def goal(_request: Any) -> dict[str, Any]:
        current = k.get_goal()
        if current is None:
            return {"success": False, "error_info": "Problem has no goal"}
        return ok(tree=condition_tree(current))

    def add_problem(request: Any) -> dict[str, Any]:
        k.load_problem(request.problem, "<add_problem request>")
        return ok()

    def exist_predicate(request: Any) -> dict[str, Any]:
        return {"exist": k.exist_predicate(node_text(request.node))}

    def exist_function(request: Any) -> dict[str, Any]:
        node = request.node
        name = "(" + " ".join([node.name, *(p.name for p in node.parameters)]) + ")"
        return {"exist": k.get_function(name) is not None}

    table: dict[str, tuple[str, Answer]] = {
        "add_problem": ("plansys2_msgs/srv/AddProblem", add_problem),
        "add_problem_goal": (
            "plansys2_msgs/srv/AddProblemGoal",
            lambda r: changed(k.set_goal(tree_text(r.tree)), "Goal not valid"),
        ),
        "add_problem_instance": (
            "plansys2_msgs/srv/AffectParam",
            lambda r: changed(
                k.add_instance(r.param.name, r.param.type),
                f"Instance {r.param.name} already exists",
            ),
        ),
        "remove_problem_instance": (
            "plansys2_msgs/srv/AffectParam",
            lambda r: changed(k.remove_instance(r.param.name), "Instance not found"),
        ),
        "add_problem_predicate": (
            affect_node,
            lambda r: changed(
                k.add_predicate(node_text(r.node)),
                f"Predicate [{node_text(r.node)}] already in the knowledge",
            ),
        ),
        "remove_problem_predicate": (
            affect_node,
            lambda r: changed(k.remove_predicate(node_text(r.node)), "Predicate not found"),
        ),
        "add_problem_function": (
            affect_node,
            lambda r: changed(k.set_function(node_text(r.node)), "Function already has it"),
        ),
        "update_problem_function": (
            affect_node,
            lambda r: (k.set_function(node_text(r.node)), ok())[1],
        ),
        "remove_problem_function": (
            affect_node,
            lambda r: changed(k.remove_function(node_text(r.node)), "Function not found"),
        ),
        "get_problem_goal": ("plansys2_msgs/srv/GetProblemGoal", goal),
        "get_problem_instance": (
            "plansys2_msgs/srv/GetProblemInstanceDetails",
            lambda r: instance(r.instance),
        ),
        "get_problem_instances": (
            "plansys2_msgs/srv/GetProblemInstances",
            lambda _r: ok(instances=[param(n, t) for n, t in k.get_instances().items()]),
        ),
        "get_problem_predicate": (details, predicate),
        "get_problem_predicates": (
            get_states,
            lambda _r: ok(states=[atom_node(a) for a in k.get_predicates()]),
        ),
        "get_problem_function": (details, function),
        "get_problem_functions": (
            get_states,
            lambda _r: ok(states=[fluent_node(f) for f in k.get_functions()]),
        ),
        "get_problem": (
            "plansys2_msgs/srv/GetProblem",
            lambda _r: ok(problem=k.get_problem_text()),
        ),
        "is_problem_goal_satisfied": (
            "plansys2_msgs/srv/IsProblemGoalSatisfied",
            lambda r: ok(satisfied=k.is_goal_satisfied(tree_text(r.tree))),
        ),
        "remove_problem_goal": (
            "plansys2_msgs/srv/RemoveProblemGoal",
            lambda _r: (k.clear_goal(), ok())[1],
        ),
        "clear_problem_knowledge": (
            "plansys2_msgs/srv/ClearProblemKnowledge",
            lambda _r: (k.clear_knowledge(), ok())[1],
        ),
        "exist_problem_predicate": (exist, exist_predicate),
        "exist_problem_function": (exist, exist_function),
    }
    return serve_table(node, "problem_expert", table)
