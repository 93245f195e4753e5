"""plansys_bridge.performers: the performer base class, the plugin registry, the simulator.

Names are imported lazily, so importing a submodule does not load the others.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from plansys_bridge.performers.base import (
        ActionFailed,
        ActionGoal,
        ActionPerformer,
        PerformerConfig,
        PerformerContext,
        arguments_match,
    )

__all__ = [
    "ActionFailed",
    "ActionGoal",
    "ActionPerformer",
    "PerformerConfig",
    "PerformerContext",
    "arguments_match",
]

_EXPORTS = dict.fromkeys(__all__, "base")


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
