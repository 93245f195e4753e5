"""Every built-in solver keeps the solver contract (:mod:`plansys_bridge.testing`),
skipped, saying why, when it is absent here (a binary not on PATH).

unified-planning starts a Python process and imports every engine, so it plans the
classical task only (its smoke test).
"""

from __future__ import annotations

from plansys_bridge.planning.solvers import DEFAULT_ORDER
from plansys_bridge.testing import SolverContract


def test_every_builtin_solver_has_a_contract_class() -> None:
    tested = {cls.solver for cls in SolverContract.__subclasses__() if cls.__module__ == __name__}
    assert tested == set(DEFAULT_ORDER)


class TestKairosContract(SolverContract):
    solver = "kairos"


class TestPopfContract(SolverContract):
    solver = "popf"


class TestOpticContract(SolverContract):
    solver = "optic"


class TestTfdContract(SolverContract):
    solver = "tfd"


class TestLpgContract(SolverContract):
    solver = "lpg"
    options = {"seed": 1}  # LPG-td searches at random: one seed, one answer


class TestFastDownwardContract(SolverContract):
    solver = "fast-downward"


class TestKairosCliContract(SolverContract):
    solver = "kairos-cli"


class TestUnifiedPlanningContract(SolverContract):
    solver = "unified-planning"
    tasks = ("classical",)
