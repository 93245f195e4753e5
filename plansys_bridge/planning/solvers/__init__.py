"""Solver plugins: discovery by name through the ``plansys_bridge.solvers`` entry points.

The built-in solvers register through the same entry points as third-party ones
(pyproject.toml); the same ``module:Class`` texts are listed here only so that an
editable install made before a solver was added still finds it. A plugin is
imported only when asked for, so a missing optional dependency of one solver never
breaks the others (:class:`~plansys_bridge.plugins.PluginRegistry`).
"""

from __future__ import annotations

from plansys_bridge.planning.solvers.base import PlanningTask, Solver, SolverOutcome
from plansys_bridge.plugins import GROUPS, PluginRegistry

ENTRY_POINT_GROUP = GROUPS["solvers"]

BUILTIN_SOLVERS: dict[str, str] = {
    "kairos": "plansys_bridge.planning.solvers.kairos:KairosSolver",
    "popf": "plansys_bridge.planning.solvers.external:PopfSolver",
    "optic": "plansys_bridge.planning.solvers.external:OpticSolver",
    "tfd": "plansys_bridge.planning.solvers.external:TfdSolver",
    "lpg": "plansys_bridge.planning.solvers.external:LpgSolver",
    "fast-downward": "plansys_bridge.planning.solvers.external:FastDownwardSolver",
    "kairos-cli": "plansys_bridge.planning.solvers.external:KairosCliSolver",
    "unified-planning": "plansys_bridge.planning.solvers.unified:UnifiedPlanningSolver",
}

DEFAULT_ORDER: tuple[str, ...] = (
    "kairos",
    "popf",
    "optic",
    "tfd",
    "lpg",
    "fast-downward",
    "kairos-cli",
    "unified-planning",
)
"""The order solvers are tried in when none is configured: the embedded default
first, then PlanSys2's own solvers (when installed), then the optional extras."""

__all__ = [
    "BUILTIN_SOLVERS",
    "DEFAULT_ORDER",
    "ENTRY_POINT_GROUP",
    "SOLVERS",
    "PlanningTask",
    "Solver",
    "SolverOutcome",
    "load_solver",
    "solver_names",
]


SOLVERS: PluginRegistry[Solver] = PluginRegistry(
    ENTRY_POINT_GROUP, Solver, "solver", builtin=BUILTIN_SOLVERS
)
"""The solvers installed (entry-point group ``plansys_bridge.solvers``)."""


def solver_names() -> list[str]:
    """Every known solver name: built-in ones in default order, then plugins."""
    names = list(DEFAULT_ORDER)
    names += [name for name in SOLVERS.names() if name not in names]
    return names


def load_solver(name: str) -> type[Solver]:
    """The solver class registered under ``name``; PluginError if unknown or broken."""
    return SOLVERS.load(name)
