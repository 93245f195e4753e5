"""The planning tests' small tasks: those of the solver contract."""

from plansys_bridge.testing.tasks import (
    CLASSICAL_DOMAIN,
    CLASSICAL_PROBLEM,
    CLASSICAL_UNSOLVABLE,
    TEMPORAL_DOMAIN,
    TEMPORAL_PROBLEM,
    classical,
    classical_unsolvable,
    concurrent,
    load,
    numeric,
    temporal,
)

__all__ = [
    "CLASSICAL_DOMAIN",
    "CLASSICAL_PROBLEM",
    "CLASSICAL_UNSOLVABLE",
    "TEMPORAL_DOMAIN",
    "TEMPORAL_PROBLEM",
    "classical",
    "classical_unsolvable",
    "concurrent",
    "load",
    "numeric",
    "temporal",
]
