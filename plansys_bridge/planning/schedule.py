"""Rescheduling a plan: every action as early as what it really depends on allows.

Solvers often serialise more than needed (one robot waits for another that touches
nothing it uses), and the executor's parallelism follows the plan's times. The plan
is turned into the same partial order the executor uses
(:func:`~plansys_bridge.planning.plan_graph.build_plan_graph`: causal links,
threats and conflicting effects, between happenings), then each happening is
placed at the earliest time its orderings allow, ``epsilon`` after the happening it
waits for, with every action keeping its duration. The result is validated; if it
is not valid or not shorter, the original plan is kept and the report says why.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.plan_graph import END, Ordering, build_plan_graph
from plansys_bridge.planning.validation import (
    DEFAULT_EPSILON,
    ValidationReport,
    initial_state,
    validate_plan,
)

__all__ = ["RescheduleReport", "reschedule", "reschedule_report"]


@dataclass(frozen=True)
class RescheduleReport:
    plan: Plan
    """The rescheduled plan, or the original when rescheduling did not help."""
    original: Plan
    makespan_before: float
    makespan_after: float
    rescheduled: bool
    message: str
    validation: ValidationReport | None = None

    @property
    def gain(self) -> float:
        return self.makespan_before - self.makespan_after


def reschedule(
    plan: Plan,
    domain: Domain,
    problem: Problem,
    *,
    state: State | None = None,
    epsilon: float = DEFAULT_EPSILON,
) -> Plan:
    """``plan`` with every action moved as early as its dependencies allow."""
    return reschedule_report(plan, domain, problem, state=state, epsilon=epsilon).plan


def reschedule_report(
    plan: Plan,
    domain: Domain,
    problem: Problem,
    *,
    state: State | None = None,
    epsilon: float = DEFAULT_EPSILON,
) -> RescheduleReport:
    """Reschedule and say what happened (makespan before and after, validity)."""
    before = plan.makespan
    start_state = state if state is not None else initial_state(domain, problem)

    def keep(message: str, validation: ValidationReport | None = None) -> RescheduleReport:
        return RescheduleReport(plan, plan, before, before, False, message, validation)

    if not plan.steps:
        return keep("empty plan")
    try:
        graph = build_plan_graph(plan, domain, start_state)
    except PlansysBridgeError as exc:
        return keep(f"not rescheduled: {exc}")
    if graph.unexplained:
        return keep(f"not rescheduled: {graph.unexplained[0]}")
    durations = [
        step.duration if g.durative else 0.0
        for step, g in zip(graph.steps, graph.ground, strict=True)
    ]
    starts = _earliest_starts(graph.orderings, durations, epsilon)
    if starts is None:
        return keep("not rescheduled: the orderings cannot all be met with this separation")
    steps = tuple(
        replace(step, time=round(t, 6)) for step, t in zip(graph.steps, starts, strict=True)
    )
    candidate = Plan(steps).sorted()
    report = validate_plan(domain, problem, candidate, state=start_state, epsilon=epsilon)
    if not report.valid:
        return keep(f"not rescheduled: the rescheduled plan is invalid ({report.message})", report)
    after = candidate.makespan
    if after >= before - 1e-9:
        return keep(f"already as early as its dependencies allow (makespan {before:.3f})", report)
    return RescheduleReport(
        candidate,
        plan,
        before,
        after,
        True,
        f"makespan {before:.3f} -> {after:.3f}",
        report,
    )


def _earliest_starts(
    orderings: tuple[Ordering, ...], durations: list[float], epsilon: float
) -> list[float] | None:
    """Least start times meeting every ordering (longest paths; None on a positive cycle)."""
    starts = [0.0] * len(durations)
    for _ in range(2 * len(durations) + 2):
        changed = False
        for o in orderings:
            source = starts[o.source] + (durations[o.source] if o.source_point == END else 0.0)
            need = source + epsilon - (durations[o.target] if o.target_point == END else 0.0)
            if need > starts[o.target] + 1e-9:
                starts[o.target] = need
                changed = True
        if not changed:
            return starts
    return None
