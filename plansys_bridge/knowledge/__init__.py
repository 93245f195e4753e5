"""The knowledge layer: what the robots know, and how conditions and effects act on it.

- :class:`State` (``state.py``): immutable snapshots of facts, fluents and objects.
- :class:`Evaluator` (``evaluation.py``): conditions, derived predicates, effects,
  ground actions and the atoms the plan graph links on.
- :class:`DomainExpert` / :class:`ProblemExpert`: PlanSys2's two experts; the
  problem expert is the live, validated, thread-safe knowledge with subscribers.

Names are imported lazily so ``import plansys_bridge.knowledge.state`` stays light.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "State": "state",
    "FluentKey": "state",
    "Evaluator": "evaluation",
    "EvaluationError": "evaluation",
    "UndefinedFluentError": "evaluation",
    "GroundAction": "grounding",
    "DomainExpert": "domain_expert",
    "ProblemExpert": "problem_expert",
    "KnowledgeChange": "changes",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
