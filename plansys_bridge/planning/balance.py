"""Plan balancing: a step its performer would run late goes to an idle object of its type.

Why: a temporal planner may give one robot two overlapping steps of the same action
(both ``cook_omelette`` steps to robot3 at 12.602 while robot1 and robot2 wait at the
cooking zone). PDDL allows it, but a robot runs one action of a kind at a time (one
performer per action kind and robot, as in PlanSys2's experiments), so the executor
runs the two one after the other and the mission takes 54.6 s where 33.6 s would do.
Searching again with another solver configuration sometimes finds the spread-out
plan, at ten times the planning cost; handing the step to a free robot repairs the
plan already found with a few validations.

How: for every step that overlaps another step of its performer (the action and its
first argument), each other object of the first parameter's type whose performer for
that action is free during the step takes its place in turn. When the validator then
stops at a later step of the original object (a step that relied on what the handed
step did for that object, such as holding what it picked), that step is handed over
too, and so on. A hand-off stands only when the plan validator
(:mod:`plansys_bridge.planning.validation`) accepts the whole plan and its executed
makespan (:func:`executed_makespan`) is shorter; the best one is kept and the search
starts again on the new plan until no hand-off shortens it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import AnyAction, Domain, Problem
from plansys_bridge.pddl.types import TypeHierarchy
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.validation import DEFAULT_EPSILON, initial_state, validate_plan

__all__ = ["Balanced", "Handoff", "balance_plan", "executed_makespan", "performer_of"]

_TOLERANCE = 1e-6


def performer_of(step: PlanStep) -> tuple[str, str]:
    """Who runs ``step``: its action for its first argument (the robot), which runs one
    such step at a time."""
    return step.action, step.arguments[0] if step.arguments else ""


def executed_makespan(plan: Plan) -> float:
    """The plan's length once each performer (one action kind of one robot, the first
    argument) runs its steps one at a time: a step starts no earlier than planned plus
    the delay its robot has gathered, nor before its performer is free. An estimate
    for ranking plans (delays passed between robots are not followed)."""
    delay: dict[str, float] = {}
    free: dict[tuple[str, str], float] = {}
    end = 0.0
    for step in sorted(plan.steps, key=lambda s: s.time):
        action, robot = performer_of(step)
        start = max(step.time + delay.get(robot, 0.0), free.get((action, robot), 0.0))
        delay[robot] = max(delay.get(robot, 0.0), start - step.time)
        free[action, robot] = start + step.duration
        end = max(end, start + step.duration)
    return end


@dataclass(frozen=True)
class Handoff:
    """One accepted hand-off: ``steps`` (plan indices, the overlapping step first) went
    from ``source`` to ``target``."""

    steps: tuple[int, ...]
    source: str
    target: str


@dataclass(frozen=True)
class Balanced:
    """The balanced plan (the given one when no hand-off shortened it)."""

    plan: Plan
    handoffs: tuple[Handoff, ...]
    before: float
    """Executed makespan of the given plan."""
    after: float
    refused: int
    """Hand-offs tried that the validator refused."""


def overlapping_steps(plan: Plan) -> list[int]:
    """Indices of steps that overlap another step of their performer, in time order."""
    by_performer: dict[tuple[str, str], list[int]] = {}
    for index, step in enumerate(plan.steps):
        if step.duration > 0:
            by_performer.setdefault(performer_of(step), []).append(index)
    found: set[int] = set()
    for indices in by_performer.values():
        for a in indices:
            for b in indices:
                if a != b and _overlap(plan.steps[a], plan.steps[b]):
                    found.add(a)
    return sorted(found, key=lambda i: (plan.steps[i].time, i))


def _overlap(a: PlanStep, b: PlanStep) -> bool:
    return a.time < b.end - _TOLERANCE and b.time < a.end - _TOLERANCE


class _Balancer:
    def __init__(
        self,
        domain: Domain,
        problem: Problem,
        state: State | None,
        epsilon: float,
        max_validations: int,
    ) -> None:
        self.domain = domain
        self.problem = problem
        self.state = state if state is not None else initial_state(domain, problem)
        self.epsilon = epsilon
        self.budget = max_validations
        self.refused = 0
        self.types = TypeHierarchy(domain)
        self.actions: dict[str, AnyAction] = {a.name.lower(): a for a in domain.actions}
        objects = {c.name.lower(): c.types[0] for c in domain.constants}
        objects.update({o.name.lower(): o.types[0] for o in problem.objects})
        self.objects = objects

    def valid(self, plan: Plan) -> tuple[bool, int | None]:
        """The validator's verdict and the failing step's index."""
        self.budget -= 1
        report = validate_plan(
            self.domain, self.problem, plan, state=self.state, epsilon=self.epsilon
        )
        return report.valid, report.failing_index

    def candidates(self, plan: Plan, index: int) -> list[str]:
        """Objects that may take step ``index`` over: of its first parameter's type,
        with their performer for the action free during the step; idle ones first."""
        step = plan.steps[index]
        action = self.actions.get(step.action)
        if action is None or not action.parameters or not step.arguments:
            return []
        source = step.arguments[0]
        accepted = action.parameters[0].types
        busy: set[str] = set()
        acting: set[str] = set()
        for other in plan.steps:
            if other is not step and _overlap(other, step):
                acting.update(other.arguments)
                if other.action == step.action and other.arguments:
                    busy.add(other.arguments[0])
        names = [
            name
            for name, type_name in self.objects.items()
            if name != source
            and name not in busy
            and self.types.is_subtype_of_any((type_name,), accepted)
        ]
        return sorted(names, key=lambda name: (name in acting, name))

    def substituted(self, step: PlanStep, source: str, target: str) -> PlanStep | None:
        """``step`` with ``target`` wherever ``source`` stood; None when a parameter
        there does not accept ``target``'s type."""
        action = self.actions.get(step.action)
        if action is None:
            return None
        params = action.parameters
        target_type = self.objects[target]
        args = list(step.arguments)
        for k, arg in enumerate(args):
            if arg != source:
                continue
            if k >= len(params) or not self.types.is_subtype_of_any(
                (target_type,), params[k].types
            ):
                return None
            args[k] = target
        return PlanStep(step.time, step.action, tuple(args), step.duration)

    def handoff(self, plan: Plan, index: int, target: str) -> tuple[Plan, Handoff] | None:
        """``plan`` with step ``index`` handed to ``target``, and the later steps of its
        object the validator shows depended on it; None when refused."""
        steps = list(plan.steps)
        source = steps[index].arguments[0]
        moved: list[int] = []
        todo: int | None = index
        while todo is not None and self.budget > 0:
            changed = self.substituted(steps[todo], source, target)
            if changed is None:
                break
            steps[todo] = changed
            moved.append(todo)
            trial = Plan(tuple(steps))
            ok, failing = self.valid(trial)
            if ok:
                return trial, Handoff(tuple(moved), source, target)
            todo = self._dependent(plan, index, failing, source, moved)
        self.refused += 1
        return None

    @staticmethod
    def _dependent(
        plan: Plan, index: int, failing: int | None, source: str, moved: Iterable[int]
    ) -> int | None:
        """The failing step when it is a later step of ``source`` not handed yet."""
        if failing is None or failing in moved:
            return None
        step = plan.steps[failing]
        if source not in step.arguments or step.time < plan.steps[index].time:
            return None
        return failing

    def best_handoff(self, plan: Plan, length: float) -> tuple[Plan, Handoff, float] | None:
        """The hand-off that shortens the executed makespan most, if any does."""
        best: tuple[Plan, Handoff, float] | None = None
        for index in overlapping_steps(plan):
            for target in self.candidates(plan, index):
                if self.budget <= 0:
                    return best
                tried = self.handoff(plan, index, target)
                if tried is None:
                    continue
                made = executed_makespan(tried[0])
                bar = best[2] if best is not None else length
                if made < bar - _TOLERANCE:
                    best = (tried[0], tried[1], made)
        return best


def balance_plan(
    domain: Domain,
    problem: Problem,
    plan: Plan,
    *,
    state: State | None = None,
    epsilon: float = DEFAULT_EPSILON,
    max_validations: int = 200,
) -> Balanced:
    """Hand overlapping steps of one performer to free objects of the same type while
    that shortens the executed makespan and the validator accepts the plan.

    ``state`` is where the plan starts (default: the problem's initial state);
    ``max_validations`` bounds the work on plans with many overlaps and candidates."""
    balancer = _Balancer(domain, problem, state, epsilon, max_validations)
    before = executed_makespan(plan)
    length = before
    handoffs: list[Handoff] = []
    while balancer.budget > 0:
        found = balancer.best_handoff(plan, length)
        if found is None:
            break
        plan, handoff, length = found
        handoffs.append(handoff)
    return Balanced(plan, tuple(handoffs), before, length, balancer.refused)
