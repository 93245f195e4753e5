"""What the plan validator says about a plan, and how it writes what it found.

:class:`ValidationReport` is the verdict :func:`~plansys_bridge.planning.validation.validate_plan`
returns; the helpers write conditions and plan times the way plan files and PDDL do,
so a message names what a reader can find in their files.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Atom, Compare, Condition, Domain, Problem
from plansys_bridge.planning.plan import PlanStep

__all__ = ["ValidationReport", "condition_text", "describe", "initial_state", "plan_time"]


@dataclass(frozen=True)
class ValidationReport:
    """The verdict on a plan. ``failing_step`` / ``failing_condition`` are set when
    a step's condition or duration fails; a missed goal sets only ``failing_condition``."""

    valid: bool
    message: str
    failing_step: PlanStep | None = None
    failing_condition: str | None = None
    failing_index: int | None = None
    """Index of the failing step in the plan as given."""
    time: float | None = None
    """When the failure happens on the plan's timeline."""
    makespan: float = 0.0
    final_state: State | None = field(default=None, compare=False, repr=False)

    def __bool__(self) -> bool:
        return self.valid

    def __str__(self) -> str:
        return self.message


def initial_state(domain: Domain, problem: Problem) -> State:
    """The problem's initial state: its facts, fluent values, objects and the constants."""
    objects = {c.name: c.types[0] for c in domain.constants}
    objects.update({o.name: o.types[0] for o in problem.objects})
    fluents = {(fv.fluent.name, tuple(fv.fluent.args)): fv.value for fv in problem.init_fluents}
    return State(problem.init, fluents, objects)


def describe(cond: Condition, state: State, ev: Evaluator, duration: float | None) -> str:
    """The condition as PDDL, with both sides' values when it is a comparison."""
    text = condition_text(cond)
    if isinstance(cond, Compare):
        try:
            left = ev.value(cond.left, state, {}, duration)
            right = ev.value(cond.right, state, {}, duration)
        except PlansysBridgeError:
            return text
        return f"{text} [{left:g} {cond.op} {right:g}]"
    return text


def condition_text(cond: Condition) -> str:
    """The condition as PDDL text."""
    try:
        from plansys_bridge.pddl.writer import write_condition
    except ImportError:
        return str(cond) if isinstance(cond, Atom) else repr(cond)
    return write_condition(cond)


def plan_time(time: float) -> str:
    """A plan time as plan files print it, without trailing zeros: ``5.0005``, ``10``."""
    return f"{time:.6f}".rstrip("0").rstrip(".")
