"""Kairos, the embedded default solver, through its Python API.

Kairos (PyPI ``kairos-planner``) plans with durative actions, numeric fluents,
derived predicates and required concurrency in a few hundredths of a second on
PlanSys2-sized tasks, and releases the GIL while it searches, so a planner running
in a worker thread does not stall the executor's event loop.

By default it returns the first plan (the executor waits on it). With
``improve_for`` seconds it then runs Kairos' anytime search within that budget
(never beyond the planner's timeout) and keeps the shorter of the two plans:
the anytime search optimises its own cost, which is not always the makespan.
``threads`` defaults to 1 so runs are reproducible.
"""

from __future__ import annotations

import time
from typing import Any, ClassVar

from pydantic import Field

from plansys_bridge.planning.capabilities import ALL_CAPABILITIES, Capability
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.solvers.base import PlanningTask, Solver, SolverOutcome
from plansys_bridge.plugins import PluginSettings

_STATUS = {
    "SOLVED": PlanStatus.SOLVED,
    "UNSOLVABLE": PlanStatus.UNSOLVABLE,
    "NO_PLAN_FOUND": PlanStatus.UNSOLVABLE,
    "TIMEOUT": PlanStatus.TIMEOUT,
    "UNSUPPORTED": PlanStatus.UNSUPPORTED,
}


class KairosSolver(Solver):
    name = "kairos"
    capabilities: ClassVar[frozenset[Capability]] = ALL_CAPABILITIES

    class Settings(PluginSettings):
        improve_for: float | None = Field(None, ge=0)
        """Seconds to keep improving the first plan found."""
        threads: int = Field(1, ge=1)
        engine: str | None = None
        search: str | None = None
        epsilon: float | None = Field(None, gt=0)
        seed: int | None = None
        memory_mb: int | None = Field(None, ge=1)

    @classmethod
    def unavailable_reason(cls) -> str | None:
        try:
            import kairos  # noqa: F401
        except ImportError as exc:
            return f"the kairos module is not installed ({exc}); pip install kairos-planner"
        return None

    @property
    def epsilon_value(self) -> float:
        return float(self.options.get("epsilon", self.epsilon))

    def _solve(self, task: PlanningTask, timeout: float) -> SolverOutcome:
        import kairos

        try:
            domain = kairos.parse_domain(task.domain_text, "domain.pddl")
            problem = kairos.parse_problem(task.problem_text, domain, "problem.pddl")
        except kairos.PddlError as exc:
            return SolverOutcome(PlanStatus.ERROR, message=_diagnostics(exc.diagnostics, task))
        kwargs: dict[str, Any] = {
            "anytime": False,
            "timeout": timeout,
            "threads": self.options.get("threads", 1),
            "epsilon": self.epsilon_value,
        }
        for option in ("engine", "search", "seed"):
            if option in self.options:
                kwargs[option] = self.options[option]
        if "memory_mb" in self.options:
            kwargs["memory_limit_mb"] = self.options["memory_mb"]
        started = time.monotonic()
        try:
            result = kairos.Planner().solve(problem, **kwargs)
        except (TypeError, KeyError, ValueError) as exc:
            return SolverOutcome(PlanStatus.ERROR, message=f"kairos rejected its options: {exc}")
        outcome = _outcome(result)
        budget = self.options.get("improve_for")
        remaining = timeout - (time.monotonic() - started)
        if budget is None or outcome.plan is None or remaining <= 0:
            return outcome
        # Anytime search for a shorter plan; the first plan stands if it finds none.
        kwargs.update(anytime=True, timeout=min(float(budget), remaining))
        better = _outcome(kairos.Planner().solve(problem, **kwargs))
        if better.plan is not None and better.plan.makespan < outcome.plan.makespan - 1e-9:
            before = outcome.plan.makespan
            return SolverOutcome(
                PlanStatus.SOLVED,
                better.plan,
                f"{better.message}; improved makespan {before:.3f} -> {better.plan.makespan:.3f}",
            )
        return SolverOutcome(
            PlanStatus.SOLVED, outcome.plan, f"{outcome.message}; no shorter plan within {budget} s"
        )


def _outcome(result: Any) -> SolverOutcome:
    status = _STATUS.get(result.status.name, PlanStatus.ERROR)
    plan = result.plan
    if plan is not None and status is not PlanStatus.ERROR:
        # An anytime search stopped by its budget still has a plan.
        steps = tuple(
            PlanStep(
                round(s.time, 6),
                s.name.lower(),
                tuple(a.lower() for a in s.args),
                round(s.duration, 6),
            )
            for s in plan.steps
        )
        return SolverOutcome(PlanStatus.SOLVED, Plan(steps), _summary(result))
    message = _summary(result)
    if result.status.name == "NO_PLAN_FOUND":
        message = f"no plan found (not proven unsolvable); {message}"
    return SolverOutcome(status, None, message)


def _summary(result: Any) -> str:
    notes = [str(d) for d in result.diagnostics]
    head = f"kairos: {result.status.name.lower()} ({result.stop_reason.name.lower()})"
    return "; ".join([head, *notes])


def _diagnostics(diagnostics: Any, task: PlanningTask) -> str:
    """Kairos's diagnostics quoted against the text it was given."""
    parts = []
    for diag in diagnostics:
        loc = diag.location
        source = task.problem_text
        if loc is not None and "domain" in str(loc):
            source = task.domain_text
        try:
            parts.append(diag.format(source))
        except Exception:  # formatting is a courtesy; the plain message still says why
            parts.append(str(diag))
    return "kairos rejected the PDDL written for it:\n" + "\n".join(parts)
