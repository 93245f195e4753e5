"""Plan execution: dependency graph, behaviour tree, executor, DOT.

The public names are importable from here; modules load on first use so that
``plansys_bridge.planning`` can use the plan graph without pulling in the hub.

* :func:`build_plan_graph` / :class:`PlanGraph` (``plan_graph``)
* :class:`Executor` (``executor``), :class:`ExecutorOptions` (``options``)
* :class:`ExecutionResult` / :class:`ActionRecord` (``results``)
* :class:`ActionNodes` for per-action templates (``tree_builder``)
* :func:`plan_graph_to_dot` (``dot``)
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from plansys_bridge.execution.dot import plan_graph_to_dot
    from plansys_bridge.execution.executor import Executor
    from plansys_bridge.execution.options import ActionTemplate, ExecutorOptions
    from plansys_bridge.execution.plan_graph import (
        Ordering,
        PlanGraph,
        PlanGraphError,
        UnexplainedRequirement,
        build_plan_graph,
    )
    from plansys_bridge.execution.results import ActionRecord, ExecutionResult, efficiency
    from plansys_bridge.execution.tree_builder import ActionNodes, TemplateError

_EXPORTS = {
    "plan_graph_to_dot": "dot",
    "Executor": "executor",
    "ActionTemplate": "options",
    "ExecutorOptions": "options",
    "Ordering": "plan_graph",
    "PlanGraph": "plan_graph",
    "PlanGraphError": "plan_graph",
    "UnexplainedRequirement": "plan_graph",
    "build_plan_graph": "plan_graph",
    "ActionRecord": "results",
    "ExecutionResult": "results",
    "efficiency": "results",
    "ActionNodes": "tree_builder",
    "TemplateError": "tree_builder",
}

__all__ = [
    "ActionNodes",
    "ActionRecord",
    "ActionTemplate",
    "ExecutionResult",
    "Executor",
    "ExecutorOptions",
    "Ordering",
    "PlanGraph",
    "PlanGraphError",
    "TemplateError",
    "UnexplainedRequirement",
    "build_plan_graph",
    "efficiency",
    "plan_graph_to_dot",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
