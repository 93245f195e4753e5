"""Greedy action elimination: drop the steps of a plan that nothing needs.

Solvers' plans sometimes carry useless steps: a pick undone by the next drop, a move
there and back. Following Fink and Yang's greedy justification, each step in turn is
taken out together with every later step that then fails (the drop whose pick is
gone); if what remains is a valid plan reaching the goal, the removal stands. Every
candidate is checked with :func:`~plansys_bridge.planning.validation.validate_plan`,
so the result is a valid plan whatever the domain (numeric effects, concurrency).
"""

from __future__ import annotations

from dataclasses import dataclass

from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.validation import DEFAULT_EPSILON, validate_plan

__all__ = ["EliminationReport", "eliminate_redundant_steps"]

MAX_STEPS = 60
"""Longer plans are left as they are: each candidate costs a validation or more."""


@dataclass(frozen=True)
class EliminationReport:
    plan: Plan
    removed: tuple[PlanStep, ...]

    @property
    def message(self) -> str:
        if not self.removed:
            return ""
        texts = ", ".join(step.text for step in self.removed)
        return f"removed {len(self.removed)} step(s) nothing needed: {texts}"


def eliminate_redundant_steps(
    domain: Domain,
    problem: Problem,
    plan: Plan,
    *,
    state: State | None = None,
    epsilon: float = DEFAULT_EPSILON,
) -> EliminationReport:
    """``plan`` without the steps whose removal (with what then fails) keeps it valid.

    ``plan`` must be valid; a plan longer than :data:`MAX_STEPS` is returned as is.
    """
    steps = list(plan.sorted().steps)
    if len(steps) > MAX_STEPS:
        return EliminationReport(plan, ())
    removed: list[PlanStep] = []
    index = 0
    while index < len(steps):
        kept = _without(domain, problem, steps, index, state, epsilon)
        if kept is None:
            index += 1
            continue
        removed += [s for s in steps if s not in kept]
        steps = kept
    if not removed:
        return EliminationReport(plan, ())
    return EliminationReport(Plan(tuple(steps)), tuple(removed))


def _without(
    domain: Domain,
    problem: Problem,
    steps: list[PlanStep],
    index: int,
    state: State | None,
    epsilon: float,
) -> list[PlanStep] | None:
    """The steps without ``steps[index]`` and the later steps that then fail, if that
    is a valid plan; None otherwise."""
    candidate = steps[:index] + steps[index + 1 :]
    while True:
        plan = Plan(tuple(candidate))
        report = validate_plan(domain, problem, plan, state=state, epsilon=epsilon)
        if report.valid:
            return candidate
        failing = report.failing_index
        # only a later step may go with it; a failing goal or earlier step: keep it
        if failing is None or failing < index or report.failing_step is None:
            return None
        candidate = candidate[:failing] + candidate[failing + 1 :]
