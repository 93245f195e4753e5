"""plansys_bridge.performers: the performer base class, the plugin registry, the simulator."""

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
