"""PlanSys2's domain expert getters and the planner's get_plan on DDS.

Names and types as PlanSys2 creates them (branch rolling):
``plansys2_domain_expert/src/plansys2_domain_expert/DomainExpertNode.cpp`` serves
``/domain_expert/get_domain_name`` (GetDomainName), ``get_domain_types``
(GetDomainTypes), ``get_domain_actions`` / ``get_domain_durative_actions``
(GetDomainActions), ``get_domain_predicates`` / ``get_domain_functions`` /
``get_domain_derived_predicates`` (GetStates), ``get_domain_predicate_details`` /
``get_domain_function_details`` (GetNodeDetails), ``get_domain_action_details``
(GetDomainActionDetails), ``get_domain_durative_action_details``
(GetDomainDurativeActionDetails), ``get_domain_derived_predicate_details``
(GetDomainDerivedPredicateDetails) and ``get_domain`` (GetDomain);
``plansys2_planner/src/plansys2_planner/PlannerNode.cpp`` serves ``/planner/get_plan``
(GetPlan: domain and problem PDDL in, ``plansys2_msgs/Plan`` out).

An action's details name its parameters ``?0``, ``?1``... in the parameter list and in
its trees, as ``DomainExpert::getAction`` does, or the objects the request lists.
"""

from __future__ import annotations

import asyncio
from typing import Any

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.interfaces.dds import dds_type, ros2_constants
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.pddl.model import Action, DurativeAction, PredicateDef, TypedName
from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.planning.planner import Planner
from plansys_bridge.ros2.node import Ros2Node
from plansys_bridge.ros2.problem_expert_services import Answer, ServiceSet, serve_table
from plansys_bridge.ros2.services import ServiceServer
from plansys_bridge.ros2.trees import condition_tree, effect_tree, param

__all__ = ["serve_domain_expert", "serve_planner"]


def _skeleton(item: Any, node_type: str) -> Any:
    """A predicate or function definition as PlanSys2 lists it: parameters with types."""
    kinds = ros2_constants("plansys2_msgs/msg/Node")
    return dds_type("plansys2_msgs/msg/Node")(
        node_type=kinds[node_type],
        name=item.name,
        parameters=[param(p.name, p.types[0]) for p in item.parameters],
    )


def _action_params(
    parameters: tuple[TypedName, ...], objects: list[str]
) -> tuple[list[Any], dict[str, str]]:
    """The parameter list and the renaming of variables PlanSys2 applies to the trees."""
    names = {p.name: objects[i] if i < len(objects) else f"?{i}" for i, p in enumerate(parameters)}
    return [param(names[p.name], p.types[0]) for p in parameters], names


def _action_details(action: Action, objects: list[str]) -> Any:
    params, names = _action_params(action.parameters, objects)
    return dds_type("plansys2_msgs/msg/Action")(
        name=action.name,
        parameters=params,
        preconditions=condition_tree(action.precondition, names),
        effects=effect_tree(action.effect, names),
    )


def _durative_details(action: DurativeAction, objects: list[str]) -> Any:
    params, names = _action_params(action.parameters, objects)
    return dds_type("plansys2_msgs/msg/DurativeAction")(
        name=action.name,
        parameters=params,
        at_start_requirements=condition_tree(action.at_start, names),
        over_all_requirements=condition_tree(action.over_all, names),
        at_end_requirements=condition_tree(action.at_end, names),
        at_start_effects=effect_tree(action.start_effect, names),
        at_end_effects=effect_tree(action.end_effect, names),
    )


def serve_domain_expert(node: Ros2Node, expert: DomainExpert) -> ServiceSet:
    """Serve PlanSys2's domain expert getters from ``expert``."""
    d = expert
    get_states = "plansys2_msgs/srv/GetStates"
    details = "plansys2_msgs/srv/GetNodeDetails"
    actions = "plansys2_msgs/srv/GetDomainActions"

    def ok(**fields: Any) -> dict[str, Any]:
        return {"success": True, **fields}

    def detail(find: Any, node_type: str, what: str) -> Answer:
        def answer(request: Any) -> dict[str, Any]:
            name = request.expression.strip("() ").split(" ")[0].lower()
            found = find(name)
            if found is None:
                return {"success": False, "error_info": f"{what} {name!r} not found"}
            return ok(node=_skeleton(found, node_type))

        return answer

    def action_detail(kind: type[Any], build: Any, field: str) -> Answer:
        def answer(request: Any) -> dict[str, Any]:
            name = getattr(request, field).strip().lower()
            found = d.get_action(name)
            if not isinstance(found, kind):
                return {"success": False, "error_info": f"{field} {name!r} not found"}
            try:
                return ok(**{field: build(found, list(request.parameters))})
            except PlansysBridgeError as exc:
                return {"success": False, "error_info": f"{field} {name!r}: {exc}"}

        return answer

    def derived_detail(request: Any) -> dict[str, Any]:
        name = request.predicate.strip("() ").split(" ")[0].lower()
        found = d.get_derived(name)
        if not found:
            return {"success": False, "error_info": f"derived predicate {name!r} not found"}
        derived_type = dds_type("plansys2_msgs/msg/Derived")
        return ok(
            predicates=[
                derived_type(
                    predicate=_skeleton(x.head, "PREDICATE"),
                    preconditions=condition_tree(x.condition),
                )
                for x in found
            ]
        )

    derived: list[PredicateDef] = [x.head for x in d.get_derived()]
    table: dict[str, tuple[str, Answer]] = {
        "get_domain_name": ("plansys2_msgs/srv/GetDomainName", lambda _r: ok(name=d.name)),
        "get_domain_types": (
            "plansys2_msgs/srv/GetDomainTypes",
            lambda _r: ok(types=d.get_types()),
        ),
        "get_domain_actions": (
            actions,
            lambda _r: ok(actions=[a.name for a in d.get_actions() if isinstance(a, Action)]),
        ),
        "get_domain_durative_actions": (
            actions,
            lambda _r: ok(actions=[a.name for a in d.get_durative_actions()]),
        ),
        "get_domain_predicates": (
            get_states,
            lambda _r: ok(states=[_skeleton(p, "PREDICATE") for p in d.get_predicates()]),
        ),
        "get_domain_functions": (
            get_states,
            lambda _r: ok(states=[_skeleton(f, "FUNCTION") for f in d.get_functions()]),
        ),
        "get_domain_derived_predicates": (
            get_states,
            lambda _r: ok(states=[_skeleton(p, "PREDICATE") for p in derived]),
        ),
        "get_domain_predicate_details": (
            details,
            detail(d.get_predicate, "PREDICATE", "predicate"),
        ),
        "get_domain_function_details": (details, detail(d.get_function, "FUNCTION", "function")),
        "get_domain_action_details": (
            "plansys2_msgs/srv/GetDomainActionDetails",
            action_detail(Action, _action_details, "action"),
        ),
        "get_domain_durative_action_details": (
            "plansys2_msgs/srv/GetDomainDurativeActionDetails",
            action_detail(DurativeAction, _durative_details, "durative_action"),
        ),
        "get_domain_derived_predicate_details": (
            "plansys2_msgs/srv/GetDomainDerivedPredicateDetails",
            derived_detail,
        ),
        "get_domain": ("plansys2_msgs/srv/GetDomain", lambda _r: ok(domain=d.get_domain_text())),
    }
    return serve_table(node, "domain_expert", table)


def serve_planner(node: Ros2Node, planner: Planner) -> ServiceSet:
    """Serve ``/planner/get_plan``: plan the PDDL a client sends with ``planner``."""
    response = dds_type("plansys2_msgs/srv/GetPlan_Response")

    async def get_plan(request: Any) -> Any:
        try:
            domain = parse_domain(request.domain, "<get_plan domain>")
            problem = parse_problem(request.problem, domain, filename="<get_plan problem>")
        except PlansysBridgeError as exc:
            return response(success=False, error_info=str(exc))
        result = await asyncio.to_thread(planner.solve, domain, problem)
        if result.plan is None:
            return response(success=False, error_info=f"no plan: {result.message}")
        plan = dds_type("plansys2_msgs/msg/Plan")(
            items=[
                dds_type("plansys2_msgs/msg/PlanItem")(
                    time=s.time, action=s.text, duration=s.duration
                )
                for s in result.plan
            ]
        )
        return response(success=True, plan=plan)

    server = ServiceServer(node, "planner/get_plan", "plansys2_msgs/srv/GetPlan", get_plan)
    return ServiceSet([server])
