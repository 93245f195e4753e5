"""Test support for extension packages: the contract suites.

``from plansys_bridge.testing import PerformerContract`` (or ``SolverContract``,
``TransportContract``) and subclass it in a test module; pytest then runs every
contract test against your plugin. The performer contract runs on the in-process
hub and the virtual clock (:mod:`plansys_bridge.testing.contract`), the solver
contract on small tasks (:mod:`~plansys_bridge.testing.solver_contract`), the
transport contract between two hubs (:mod:`~plansys_bridge.testing.transport_contract`).

Names are imported lazily: the pytest plugin loads this package in every test run.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from plansys_bridge.testing.contract import PerformerContract
    from plansys_bridge.testing.solver_contract import SolverContract
    from plansys_bridge.testing.transport_contract import TransportContract

__all__ = ["PerformerContract", "SolverContract", "TransportContract"]

_MODULES = {
    "PerformerContract": "contract",
    "SolverContract": "solver_contract",
    "TransportContract": "transport_contract",
}


def __getattr__(name: str) -> Any:
    module = _MODULES.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
