"""Solver plugins: discovery by name through the ``plansys_bridge.solvers`` entry points.

The built-in solvers are also listed here as lazy ``module:Class`` references, so
they are found even when the package metadata is stale (an editable install made
before a solver was added); third-party solvers register an entry point. A plugin
is imported only when asked for, so a missing optional dependency of one solver
never breaks the others.
"""

from __future__ import annotations

import functools
import importlib
from importlib.metadata import entry_points

from plansys_bridge.errors import PluginError
from plansys_bridge.planning.solvers.base import PlanningTask, Solver, SolverOutcome

ENTRY_POINT_GROUP = "plansys_bridge.solvers"

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
    "PlanningTask",
    "Solver",
    "SolverOutcome",
    "load_solver",
    "solver_names",
]


@functools.lru_cache(maxsize=1)
def _registered() -> dict[str, str]:
    """Entry points of the group, read once (scanning the installed packages is slow)."""
    return {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP)}


def solver_names() -> list[str]:
    """Every known solver name: built-in ones in default order, then plugins."""
    names = list(DEFAULT_ORDER)
    names += [name for name in _registered() if name not in names]
    return names


def load_solver(name: str) -> type[Solver]:
    """The solver class registered under ``name``; PluginError if unknown or broken."""
    reference = _registered().get(name) or BUILTIN_SOLVERS.get(name)
    if reference is None:
        known = ", ".join(solver_names())
        raise PluginError(f"unknown solver {name!r} (known: {known})")
    module_name, _, attr = reference.partition(":")
    try:
        cls = getattr(importlib.import_module(module_name), attr)
    except (ImportError, AttributeError) as exc:
        raise PluginError(f"solver {name!r} ({reference}) cannot be loaded: {exc}") from exc
    if not (isinstance(cls, type) and issubclass(cls, Solver)):
        raise PluginError(f"solver {name!r} ({reference}) is not a Solver subclass")
    return cls
