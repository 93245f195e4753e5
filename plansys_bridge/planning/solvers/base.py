"""The solver plugin interface.

A solver declares the PDDL features it plans with (:attr:`Solver.capabilities`) and
the options it accepts (:attr:`Solver.option_types`); :meth:`Solver.solve` checks
both, writes the task as PDDL with the project's writer (never the user's original
text: PlanSys2's files carry terminal commands after the closing parenthesis, which
strict solvers reject) and delegates to the one method a plugin implements,
:meth:`Solver._solve`. Every expected failure comes back as a :class:`PlanResult`
whose message says why, in the solver's own words.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, ClassVar

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.capabilities import Capability, describe, required_capabilities
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.result import PlanResult, PlanStatus


@dataclass(frozen=True)
class PlanningTask:
    """A domain and problem, as model and as the PDDL text handed to solvers."""

    domain: Domain
    problem: Problem
    domain_text: str
    problem_text: str

    @classmethod
    def from_model(cls, domain: Domain, problem: Problem) -> PlanningTask:
        """The texts solvers get. The problem names the domain it is planned in (as
        PlanSys2's problem expert writes it), whatever its file said: PlanSys2's own
        test problems leave ``(:domain )`` empty."""
        from plansys_bridge.pddl.writer import write_domain, write_problem

        if problem.domain_name != domain.name:
            problem = replace(problem, domain_name=domain.name)
        return cls(domain, problem, write_domain(domain), write_problem(problem))


@dataclass(frozen=True)
class SolverOutcome:
    """What :meth:`Solver._solve` reports; the public ``solve`` adds name and timing."""

    status: PlanStatus
    plan: Plan | None = None
    message: str = ""


class Solver(ABC):
    """Base class of every solver plugin (entry-point group ``plansys_bridge.solvers``)."""

    name: ClassVar[str] = "solver"
    capabilities: ClassVar[frozenset[Capability]] = frozenset()
    option_types: ClassVar[Mapping[str, type | tuple[type, ...]]] = {}
    """Accepted options and their types; anything else is a configuration error."""
    epsilon: ClassVar[float] = 0.001
    """Separation the solver keeps between dependent happenings (for validation)."""

    def __init__(self, options: Mapping[str, Any] | None = None) -> None:
        self.options: dict[str, Any] = {}
        for key, value in (options or {}).items():
            expected = self.option_types.get(key)
            if expected is None:
                known = ", ".join(sorted(self.option_types)) or "none"
                raise ConfigError(
                    f"unknown option for solver {self.name!r} (known: {known})",
                    key=f"solvers.{self.name}.{key}",
                )
            if isinstance(value, bool) and expected in (int, float, (int, float)):
                raise ConfigError(
                    f"expected a number, got {value!r}", key=f"solvers.{self.name}.{key}"
                )
            if expected is float and isinstance(value, int):
                value = float(value)
            if not isinstance(value, expected):
                raise ConfigError(
                    f"expected {_type_name(expected)}, got {value!r}",
                    key=f"solvers.{self.name}.{key}",
                )
            self.options[key] = value

    # ------------------------------------------------------------ declarations

    @classmethod
    def unavailable_reason(cls) -> str | None:
        """None when the solver can run here, else why not (binary missing, ...)."""
        return None

    def availability(self) -> str | None:
        """Like :meth:`unavailable_reason`, for this instance's options (an explicit path)."""
        return self.unavailable_reason()

    def missing_capabilities(self, required: frozenset[Capability]) -> frozenset[Capability]:
        return required - self.capabilities

    # ------------------------------------------------------------ solving

    def solve(self, domain: Domain, problem: Problem, timeout: float = 30.0) -> PlanResult:
        """Plan ``problem``; the elapsed time includes writing the PDDL and reading the plan."""
        started = time.monotonic()

        def result(outcome: SolverOutcome) -> PlanResult:
            return PlanResult(
                outcome.status,
                outcome.plan,
                self.name,
                outcome.message,
                time.monotonic() - started,
            )

        reason = self.availability()
        if reason is not None:
            return result(SolverOutcome(PlanStatus.UNSUPPORTED, message=reason))
        missing = self.missing_capabilities(required_capabilities(domain, problem))
        if missing:
            return result(
                SolverOutcome(
                    PlanStatus.UNSUPPORTED,
                    message=f"the task uses {describe(missing)}, "
                    f"which {self.name} does not support",
                )
            )
        if not 0 < timeout < math.inf:
            raise ConfigError(f"timeout must be positive and finite, got {timeout}", key="timeout")
        try:
            task = PlanningTask.from_model(domain, problem)
            outcome = self._solve(task, timeout)
        except PlansysBridgeError as exc:
            outcome = SolverOutcome(PlanStatus.ERROR, message=str(exc))
        except OSError as exc:  # the run folder could not be written, the program not run
            outcome = SolverOutcome(PlanStatus.ERROR, message=f"{self.name}: {exc}")
        if outcome.status is PlanStatus.SOLVED and outcome.plan is None:
            outcome = SolverOutcome(
                PlanStatus.ERROR, message="solver reported success without a plan"
            )
        return result(outcome)

    @abstractmethod
    def _solve(self, task: PlanningTask, timeout: float) -> SolverOutcome:
        """Plan ``task`` within ``timeout`` seconds; the one method a plugin implements."""


def _type_name(expected: type | tuple[type, ...]) -> str:
    if isinstance(expected, tuple):
        return " or ".join(t.__name__ for t in expected)
    return expected.__name__
