"""The contract every solver plugin keeps, as tests a solver package inherits.

Subclass :class:`SolverContract` in a test module and name your solver as it is
registered in the ``plansys_bridge.solvers`` entry-point group::

    class TestMySolver(SolverContract):
        solver = "my-solver"
        options = {"seed": 1}      # optional: options every test builds it with

What is checked: the name is registered and the class declares its capabilities and
a pydantic ``Settings``; it plans every small task whose features it declares (the
plan validates with the solver's own separation) and refuses the others naming the
missing features; it never reports a plan for an unsolvable task and says why; a
timeout is honoured (the call returns, with a plan only if it found one); unknown
options and options of the wrong type are ConfigErrors naming the key. When the
solver cannot run here (a binary missing) every test skips with its reason.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, ClassVar

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.capabilities import ALL_CAPABILITIES, required_capabilities
from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.solvers import SOLVERS, Solver
from plansys_bridge.planning.validation import validate_plan
from plansys_bridge.plugins import PluginSettings
from plansys_bridge.testing import tasks

__all__ = ["SolverContract"]

TASKS: dict[str, Callable[[], tuple[Domain, Problem]]] = {
    "classical": tasks.classical,
    "temporal": tasks.temporal,
    "numeric": tasks.numeric,
    "concurrent": tasks.concurrent,
}


class SolverContract:
    """Inherit to run the solver contract; set ``solver`` (and ``options``)."""

    solver: ClassVar[str] = ""
    """The name the solver is registered under."""
    options: ClassVar[dict[str, Any]] = {}
    """Options every test builds the solver with (e.g. a seed for a random search)."""
    tasks: ClassVar[tuple[str, ...]] = tuple(TASKS)
    """The small tasks tried (a slow solver may limit itself to ``("classical",)``)."""
    timeout: ClassVar[float] = 20.0
    """Seconds a small task may take."""
    grace: ClassVar[float] = 30.0
    """Seconds beyond its timeout a solver may take to stop and report."""

    def solver_class(self) -> type[Solver]:
        cls = SOLVERS.load(self.solver)
        reason = cls.unavailable_reason()
        if reason is not None:
            pytest.skip(f"{self.solver}: {reason}")
        return cls

    def make(self, **options: Any) -> Solver:
        return self.solver_class()({**self.options, **options})

    def test_contract_registered_with_its_declarations(self) -> None:
        cls = SOLVERS.load(self.solver)
        assert self.solver in SOLVERS.names()
        assert cls.capabilities <= ALL_CAPABILITIES
        assert cls.epsilon > 0
        assert issubclass(cls.Settings, PluginSettings)

    def test_contract_plans_what_it_supports(self) -> None:
        solver = self.make()
        for name in self.tasks:
            domain, problem = TASKS[name]()
            missing = solver.missing_capabilities(required_capabilities(domain, problem))
            result = solver.solve(domain, problem, timeout=self.timeout)
            assert result.solver == solver.name and result.elapsed_s >= 0
            if missing:
                assert result.status is PlanStatus.UNSUPPORTED, f"{name}: {result}"
                assert all(str(cap) in result.message for cap in missing), result.message
                continue
            assert result.status is PlanStatus.SOLVED, f"{name}: {result}"
            assert result.plan is not None and len(result.plan) > 0
            report = validate_plan(domain, problem, result.plan, epsilon=solver.epsilon)
            assert report.valid, f"{name}: {report.message}\n{result.plan.to_text(4)}"

    def test_contract_reports_no_plan(self) -> None:
        domain, problem = tasks.classical_unsolvable()
        solver = self.make()
        result = solver.solve(domain, problem, timeout=self.timeout)
        assert result.status is not PlanStatus.SOLVED and result.plan is None, str(result)
        assert result.message, "a solver that finds no plan must say why"
        if not solver.missing_capabilities(required_capabilities(domain, problem)):
            # a crash on an unsolvable task (LPG-td) is an error with its exit status
            allowed = (PlanStatus.UNSOLVABLE, PlanStatus.ERROR, PlanStatus.TIMEOUT)
            assert result.status in allowed, str(result)

    def test_contract_honours_the_timeout(self) -> None:
        domain, problem = tasks.temporal()
        solver = self.make()
        if solver.missing_capabilities(required_capabilities(domain, problem)):
            domain, problem = tasks.classical()
        limit = 0.05
        started = time.monotonic()
        result = solver.solve(domain, problem, timeout=limit)
        took = time.monotonic() - started
        assert took < limit + self.grace, f"{self.solver} took {took:.1f} s for a {limit} s limit"
        assert result.status in (PlanStatus.SOLVED, PlanStatus.TIMEOUT, PlanStatus.ERROR)
        assert (result.plan is not None) == (result.status is PlanStatus.SOLVED), str(result)

    def test_contract_options_errors_name_the_key(self) -> None:
        cls = self.solver_class()
        with pytest.raises(ConfigError) as err:
            cls({"no_such_option": 1})
        assert err.value.key == f"solvers.{cls.name}.no_such_option"
        fields = cls.Settings.model_fields
        if not fields:
            return
        key, field = sorted(fields.items())[0]
        wrong: object = 3 if "str" in str(field.annotation) else "text"
        with pytest.raises(ConfigError) as err:
            cls({key: wrong})
        assert err.value.key == f"solvers.{cls.name}.{key}"
