"""The planner: picks the first configured solver that can plan the task, and runs it.

Unlike PlanSys2, which uses only its first plugin whatever the task, the planner
reads the features the task uses (:func:`required_capabilities`) and skips solvers
that lack one or are not installed, saying so. The order is the configured list,
or :data:`DEFAULT_ORDER` (Kairos first, embedded, then PlanSys2's own solvers when
found, then the optional extras). With ``fallback=True`` a solver that errs or
times out hands over to the next one that fits.

Options: a mapping whose keys are either solver names (mapping to that solver's
options, e.g. ``{"kairos": {"improve_for": 5}}``) or option names given to every
configured solver that accepts them (``{"threads": 1}``).

A :class:`Planner` holds no mutable state after construction, so one instance may
be used from several threads (the executor plans in a worker thread).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

from plansys_bridge.errors import ConfigError
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.capabilities import describe, required_capabilities
from plansys_bridge.planning.result import PlanResult, PlanStatus
from plansys_bridge.planning.solvers import DEFAULT_ORDER, Solver, load_solver

__all__ = ["PlanResult", "PlanStatus", "Planner"]


class Planner:
    def __init__(
        self,
        solvers: Sequence[str] | None = None,
        timeout: float = 30.0,
        options: Mapping[str, Any] | None = None,
        *,
        fallback: bool = False,
        validate: bool = False,
        eliminate: bool = False,
    ) -> None:
        if isinstance(solvers, str):
            solvers = [solvers]
        if not 0 < timeout < math.inf:
            raise ConfigError(f"timeout must be positive and finite, got {timeout}", key="timeout")
        self.timeout = float(timeout)
        self.fallback = fallback
        self.validate = validate
        self.eliminate = eliminate
        """With ``validate``: drop the steps nothing needs (greedy action elimination,
        :mod:`plansys_bridge.planning.elimination`); costs a validation per step."""
        names = list(solvers) if solvers else list(DEFAULT_ORDER)
        if not names:
            raise ConfigError("no solver configured", key="solvers")
        options = dict(options or {})
        per_solver = {k: v for k, v in options.items() if k in names and isinstance(v, Mapping)}
        common = {k: v for k, v in options.items() if k not in per_solver}
        classes = [load_solver(name) for name in names]
        for key in common:
            if not any(key in cls.option_types for cls in classes):
                raise ConfigError(
                    f"no configured solver ({', '.join(names)}) accepts this option",
                    key=f"solvers.{key}",
                )
        self.solvers: list[Solver] = []
        for name, cls in zip(names, classes, strict=True):
            opts = {k: v for k, v in common.items() if k in cls.option_types}
            opts.update(per_solver.get(name, {}))
            self.solvers.append(cls(opts))

    def candidates(self, domain: Domain, problem: Problem) -> tuple[list[Solver], list[str]]:
        """Solvers that can plan this task, in order, and why the others cannot."""
        required = required_capabilities(domain, problem)
        usable: list[Solver] = []
        skipped: list[str] = []
        for solver in self.solvers:
            reason = solver.availability()
            if reason is None:
                missing = solver.missing_capabilities(required)
                if missing:
                    reason = f"{solver.name} does not support {describe(missing)}"
            if reason is None:
                usable.append(solver)
            else:
                skipped.append(reason)
        return usable, skipped

    def solve(self, domain: Domain, problem: Problem) -> PlanResult:
        started = time.monotonic()
        usable, skipped = self.candidates(domain, problem)
        if not usable:
            return PlanResult(
                PlanStatus.UNSUPPORTED,
                None,
                ",".join(s.name for s in self.solvers),
                "no configured solver can plan this task: " + "; ".join(skipped),
                time.monotonic() - started,
            )
        failures: list[str] = []
        result: PlanResult | None = None
        for solver in usable:
            remaining = self.timeout - (time.monotonic() - started)
            if remaining <= 0:
                break
            result = solver.solve(domain, problem, remaining)
            if result.solved and self.validate:
                result = self._validated(result, solver, domain, problem)
            if result.status in (PlanStatus.SOLVED, PlanStatus.UNSOLVABLE) or not self.fallback:
                break
            failures.append(str(result))
        assert result is not None
        if failures and result.status not in (PlanStatus.SOLVED, PlanStatus.UNSOLVABLE):
            message = "; ".join(failures)
        elif failures:
            message = f"{result.message} (after: {'; '.join(failures)})"
        else:
            message = result.message
        return PlanResult(
            result.status,
            result.plan,
            result.solver,
            message,
            time.monotonic() - started,
            result.validation,
        )

    def _validated(
        self, result: PlanResult, solver: Solver, domain: Domain, problem: Problem
    ) -> PlanResult:
        from plansys_bridge.planning.elimination import eliminate_redundant_steps
        from plansys_bridge.planning.validation import validate_plan

        assert result.plan is not None
        report = validate_plan(domain, problem, result.plan, epsilon=solver.epsilon)
        if report.valid:
            plan, message = result.plan, result.message
            pruned = (
                eliminate_redundant_steps(domain, problem, plan, epsilon=solver.epsilon)
                if self.eliminate
                else None
            )
            if pruned is not None and pruned.removed:
                plan = pruned.plan
                message = f"{message}; {pruned.message}" if message else pruned.message
                report = validate_plan(domain, problem, plan, epsilon=solver.epsilon)
            return PlanResult(result.status, plan, result.solver, message, result.elapsed_s, report)
        return PlanResult(
            PlanStatus.ERROR,
            result.plan,
            result.solver,
            f"{solver.name} returned an invalid plan: {report.message}",
            result.elapsed_s,
            report,
        )
