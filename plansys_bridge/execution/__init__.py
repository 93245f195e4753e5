"""Plan execution: behaviour tree, executor, DOT, and the plan graph they run from.

The public names are importable from here; modules load on first use, so that
importing one name does not pull in the hub.

* :func:`build_plan_graph` / :class:`PlanGraph` (:mod:`plansys_bridge.planning.plan_graph`:
  the planning layer checks and reschedules plans with it too)
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
    from plansys_bridge.execution.results import ActionRecord, ExecutionResult, efficiency
    from plansys_bridge.execution.tree_builder import ActionNodes, TemplateError
    from plansys_bridge.planning.plan_graph import (
        Ordering,
        PlanGraph,
        PlanGraphError,
        UnexplainedRequirement,
        build_plan_graph,
    )

_EXPORTS = {
    "plan_graph_to_dot": "dot",
    "Executor": "executor",
    "ActionTemplate": "options",
    "ExecutorOptions": "options",
    "Ordering": "plansys_bridge.planning.plan_graph",
    "PlanGraph": "plansys_bridge.planning.plan_graph",
    "PlanGraphError": "plansys_bridge.planning.plan_graph",
    "UnexplainedRequirement": "plansys_bridge.planning.plan_graph",
    "build_plan_graph": "plansys_bridge.planning.plan_graph",
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
    path = module if module.startswith("plansys_bridge.") else f"{__name__}.{module}"
    value = getattr(importlib.import_module(path), name)
    globals()[name] = value
    return value
