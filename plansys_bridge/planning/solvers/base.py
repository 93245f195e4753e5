"""The solver plugin interface.

A solver declares the PDDL features it plans with (:attr:`Solver.capabilities`) and
the options it accepts (its pydantic :attr:`Solver.Settings`); :meth:`Solver.solve` checks
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

from pydantic import BaseModel

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.capabilities import Capability, describe, required_capabilities
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.result import PlanResult, PlanStatus
from plansys_bridge.plugins import NoSettings, validate_settings


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
    Settings: ClassVar[type[BaseModel]] = NoSettings
    """The options a mission's ``planner.options`` may give, as a pydantic model
    (:class:`~plansys_bridge.plugins.PluginSettings`); anything else is an error."""
    option_types: ClassVar[Mapping[str, Any]] = {}
    """The option names and types of ``Settings`` (derived, read-only)."""
    epsilon: ClassVar[float] = 0.001
    """Separation the solver keeps between dependent happenings (for validation)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.option_types = {n: f.annotation for n, f in cls.Settings.model_fields.items()}

    def __init__(self, options: Mapping[str, Any] | None = None) -> None:
        self.settings = validate_settings(
            self.Settings, dict(options or {}), key=f"solvers.{self.name}"
        )
        self.options: dict[str, Any] = self.settings.model_dump(exclude_unset=True)
        """The options given (not the defaults), by name."""

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
