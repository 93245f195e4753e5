"""Checking a temporal plan against a domain and the knowledge, before running it.

PlanSys2 executes whatever its solver printed. Here a plan is simulated on the
timeline with the same condition semantics the executor uses (the knowledge
:class:`~plansys_bridge.knowledge.evaluation.Evaluator`):

* every durative step has a start and an end happening; a plain ``:action`` is one
  instantaneous happening at its time;
* ``at start`` conditions hold in the state just before the start, ``at end`` just
  before the end, ``over all`` in every state strictly inside the interval (after
  the start effects, up to the end), the goal after the last happening;
* the step's duration satisfies the action's duration constraint;
* happenings at the same time must not interfere: no effect of one touches what
  another reads or changes (PDDL 2.1 mutex); interfering happenings closer than
  ``epsilon`` are refused too, as VAL does.

The report names the first failing step (in time order) and the failing part of the
condition, with numeric values where they explain the failure. Conditions and
effects are evaluated lifted, with each step's bindings (substituting the arguments
into every formula of every step was a third of a validation); what interferes is
worked out by :mod:`~plansys_bridge.planning.mutex`. A plain action's condition,
effect and footprint come from one grounding per happening
(:mod:`~plansys_bridge.planning.ground_parts`), and its adds and deletes go into a
:class:`~plansys_bridge.planning.validation_state.WorkingState` rather than a new
state snapshot each: the planner validates every plan it returns, so this is on the
way from knowledge to plan.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.grounding import substitute_condition
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import (
    And,
    BinaryOp,
    Condition,
    Domain,
    DurationConstraint,
    DurativeAction,
    Negate,
    Number,
    Problem,
)
from plansys_bridge.pddl.walkers import iter_nodes
from plansys_bridge.planning.happenings import SAME_TIME, Happening, simultaneous
from plansys_bridge.planning.mutex import (
    Footprint,
    Footprints,
    GroundParts,
    interference,
)
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.validation_report import (
    ValidationReport,
    describe,
    initial_state,
    plan_time,
)
from plansys_bridge.planning.validation_state import WorkingState
from plansys_bridge.planning.validation_steps import StepProblem, Timeline

__all__ = ["DEFAULT_EPSILON", "ValidationReport", "initial_state", "validate_plan"]

DEFAULT_EPSILON = 0.001
_SLACK = 1e-6


class _Prints:
    """The footprints of one group of simultaneous happenings, worked out on first use:
    only simultaneous steps and happenings closer than epsilon are compared, and
    computing every footprint was most of a validation's time."""

    def __init__(self, validator: _Validator, group: list[Happening], now: WorkingState) -> None:
        self._validator = validator
        self._group = group
        # the evaluator works out what a happening that is not plain touches, in the
        # state of its time
        self._state = now.state() if any(h.parts is None for h in group) else None
        self._prints: list[tuple[Happening, GroundParts | Footprint]] | None = None

    def get(self) -> list[tuple[Happening, GroundParts | Footprint]]:
        """Each happening with what it touches: its parts when it is plain."""
        if self._prints is None:
            self._prints = [
                (h, h.parts if h.parts is not None else self._asked(h)) for h in self._group
            ]
        return self._prints

    def _asked(self, h: Happening) -> Footprint:
        assert self._state is not None  # set when a happening is not plain
        return self._validator.footprints.of(h.condition, h.effect, h.bindings, self._state)


class _Invalid(Exception):
    def __init__(self, report: ValidationReport) -> None:
        self.report = report


def validate_plan(
    domain: Domain,
    problem: Problem,
    plan: Plan,
    *,
    state: State | None = None,
    epsilon: float = DEFAULT_EPSILON,
    duration_tolerance: float = 0.001,
) -> ValidationReport:
    """Validate ``plan`` from ``state`` (default: the problem's initial state)."""
    validator = _Validator(domain, problem, plan, state, epsilon, duration_tolerance)
    try:
        return validator.run()
    except _Invalid as exc:
        return exc.report


class _Validator:
    def __init__(
        self,
        domain: Domain,
        problem: Problem,
        plan: Plan,
        state: State | None,
        epsilon: float,
        duration_tolerance: float,
    ) -> None:
        self.domain = domain
        self.problem = problem
        self.plan = plan
        self.ev = Evaluator(domain)
        self.footprints = Footprints(self.ev)
        self._constant_durations: dict[int, float] = {}
        self.state = state if state is not None else initial_state(domain, problem)
        self.timeline = Timeline(self.ev, self.footprints, self.state)
        self._over_all = self.timeline.over_all
        self._over_all_reads: dict[int, set[tuple[str, tuple[str, ...]]] | None] = {}
        """What each open step's over-all condition reads (None: depends on the state)."""
        self.epsilon = epsilon
        self.duration_tolerance = duration_tolerance

    # ------------------------------------------------------------ reporting

    def fail(
        self,
        index: int | None,
        message: str,
        condition: str | None = None,
        time: float | None = None,
    ) -> _Invalid:
        step = self.plan.steps[index] if index is not None else None
        where = ""
        if index is not None and step is not None:
            where = f"step {index + 1} {step.text} at {plan_time(step.time)}: "
        return _Invalid(
            ValidationReport(
                False,
                f"plan invalid: {where}{message}",
                step,
                condition,
                index,
                time,
                self.plan.makespan,
            )
        )

    # ------------------------------------------------------------ the simulation

    def run(self) -> ValidationReport:
        try:
            happenings = self.timeline.happenings(self.plan.steps)
        except StepProblem as exc:
            raise self.fail(exc.index, exc.message) from exc
        now = WorkingState(self.state)
        open_steps: dict[int, Happening] = {}
        recent: list[tuple[float, _Prints]] = []
        for group in simultaneous(happenings):
            self._group(group, now, open_steps, recent)
        for h in open_steps.values():  # only reachable with inconsistent input
            raise self.fail(h.index, "never ends")
        state = now.state()
        self._goal(state)
        return ValidationReport(
            True,
            f"plan valid: {len(self.plan)} steps, makespan {self.plan.makespan:.3f}",
            makespan=self.plan.makespan,
            final_state=state,
        )

    def _group(
        self,
        group: list[Happening],
        state: WorkingState,
        open_steps: dict[int, Happening],
        recent: list[tuple[float, _Prints]],
    ) -> None:
        now = group[0].time
        prints = _Prints(self, group, state)
        for h in group:
            if h.point == "start":
                self._check_duration(h, state)
            parts = h.parts
            if parts is not None and parts.literals and parts.holds(state):
                continue  # a conjunction of literals, looked up directly
            try:
                self._check(h, h.condition, h.when, state)
            except _Invalid as exc:
                raise self._explain_simultaneous(exc, h, prints.get()) from None
        several = len(group) > 1 and len({h.index for h in group}) > 1
        pairs = prints.get() if several else []
        for a in range(len(pairs)):
            for b in range(a + 1, len(pairs)):
                ha, fa = pairs[a]
                hb, fb = pairs[b]
                if ha.index == hb.index:
                    continue
                shared = interference(fa, fb)
                if shared is not None:
                    other = self.plan.steps[ha.index]
                    raise self.fail(
                        hb.index,
                        f"its {hb.point} interferes with the {ha.point} of step "
                        f"{ha.index + 1} {other.text} at the same time (both touch {shared})",
                        shared,
                        now,
                    )
        self._check_separation(now, prints, recent)
        changed = self._apply(group, state, now)
        check: list[int] = []
        reads = self._over_all_reads
        for h in group:
            if h.point == "start":
                open_steps[h.index] = h
                check.append(h.index)
                parts = self._over_all.get(h.index)
                reads[h.index] = None if parts is None else parts.reads()
            elif h.point == "end":
                open_steps.pop(h.index, None)
        if changed:
            # An over-all condition held after its start and at every change since;
            # changes to nothing it reads leave it true.
            for index in open_steps:
                if index not in check:
                    read = reads[index]
                    if read is None or not changed.isdisjoint(read):
                        check.append(index)
        for index in sorted(check):
            h = open_steps[index]
            if h.time + (h.duration or 0.0) - now <= SAME_TIME:
                continue
            parts = self._over_all.get(index)
            if parts is None or not parts.literals or not parts.holds(state):
                self._check(h, h.bound.over_all, "over all condition", state, now)

    def _apply(self, group: list[Happening], state: WorkingState, now: float) -> set[object]:
        """Apply the group's effects to ``state``; every atom (as ``(predicate,
        arguments)``) and fluent they changed.

        Each happening's effect is worked out in the state after those before it in
        the group (for distinct steps the mutex check has made the order irrelevant;
        the start and end of one step at one time apply in that order).
        """
        changed: set[object] = set()
        for h in group:
            parts = h.parts
            if parts is not None and parts.plain_effect:
                state.change(parts.adds, parts.deletes)
                changed.update(parts.adds, parts.deletes)
                continue
            try:
                adds, deletes, values = self.ev.changes(
                    h.effect, state.state(), h.bindings, h.duration
                )
            except PlansysBridgeError as exc:
                raise self.fail(
                    h.index, f"{h.point} effect cannot be applied: {exc}", None, now
                ) from exc
            state.apply(adds, deletes, values)
            changed.update([(a.predicate, a.args) for a in adds])
            changed.update([(a.predicate, a.args) for a in deletes])
            changed.update(values)
        return changed

    def _explain_simultaneous(
        self,
        exc: _Invalid,
        h: Happening,
        prints: list[tuple[Happening, GroundParts | Footprint]],
    ) -> _Invalid:
        """A condition false only because its achiever happens at the same time: say so."""
        failing = exc.report.failing_condition
        for other, print_ in prints:
            if other.index == h.index or failing is None:
                continue
            footprint = print_.footprint() if isinstance(print_, GroundParts) else print_
            if failing in {str(a) for a in footprint.adds | footprint.deletes}:
                step = self.plan.steps[other.index]
                hint = (
                    f" (the {other.point} of step {other.index + 1} {step.text} changes it "
                    f"at the same time; happenings that depend on each other must be "
                    f"{self.epsilon:g} apart)"
                )
                report = replace(exc.report, message=exc.report.message + hint)
                return _Invalid(report)
        return exc

    def _check_separation(
        self,
        now: float,
        prints: _Prints,
        recent: list[tuple[float, _Prints]],
    ) -> None:
        """Interfering happenings must be at least ``epsilon`` apart."""
        recent[:] = [(t, p) for t, p in recent if now - t < self.epsilon - _SLACK]
        for then, earlier in recent:
            for ha, fa in earlier.get():
                for hb, fb in prints.get():
                    if ha.index == hb.index:
                        continue
                    shared = interference(fa, fb)
                    if shared is not None:
                        other = self.plan.steps[ha.index]
                        raise self.fail(
                            hb.index,
                            f"its {hb.point} is only {plan_time(now - then)} after the "
                            f"{ha.point} of "
                            f"step {ha.index + 1} {other.text} and both touch {shared} "
                            f"(happenings that interfere must be {self.epsilon:g} apart)",
                            shared,
                            now,
                        )
        recent.append((now, prints))

    def _check_duration(self, h: Happening, state: WorkingState) -> None:
        action = h.bound.action
        if not isinstance(action, DurativeAction) or h.duration is None:
            return
        for constraint in action.duration:
            value = self._duration_bound(h, constraint, state)
            tol = self.duration_tolerance
            op = constraint.op
            if op == "=":
                ok = abs(h.duration - value) <= tol
            elif op == "<=":
                ok = h.duration <= value + tol
            else:
                ok = h.duration >= value - tol
            if not ok:
                text = f"(?duration {constraint.op} {value:g})"
                raise self.fail(
                    h.index,
                    f"duration {h.duration:g} does not satisfy {constraint.op} {value:g}",
                    text,
                    h.time,
                )

    def _duration_bound(
        self, h: Happening, constraint: DurationConstraint, state: WorkingState
    ) -> float:
        """The value a step's duration is compared with; one made of numbers only is
        worked out once per action."""
        known = self._constant_durations.get(id(constraint))
        if known is not None:
            return known
        try:
            value = self.ev.value(constraint.value, state.state(), h.bindings)
        except PlansysBridgeError as exc:
            raise self.fail(h.index, f"duration cannot be evaluated: {exc}", None, h.time) from exc
        if all(isinstance(n, Number | BinaryOp | Negate) for n in iter_nodes(constraint.value)):
            self._constant_durations[id(constraint)] = value
        return value

    def _check(
        self,
        h: Happening,
        cond: Condition,
        when: str,
        now: WorkingState,
        time: float | None = None,
    ) -> None:
        """Raise naming the failing part unless ``cond`` holds (the evaluator's way:
        plain conjunctions of literals are looked up before coming here)."""
        state = now.state()
        try:
            if self.ev.holds(cond, state, h.bindings, h.duration):
                return
            failing = self._first_false(cond, state, h.duration, h.bindings)
        except PlansysBridgeError as exc:
            raise self.fail(
                h.index,
                f"{when} cannot be evaluated: {exc}",
                None,
                time if time is not None else h.time,
            ) from exc
        text = describe(substitute_condition(failing, h.bindings), state, self.ev, h.duration)
        moment = time if time is not None else h.time
        suffix = f" at {plan_time(moment)}" if when.startswith("over all") else ""
        raise self.fail(h.index, f"{when} {text} is false{suffix}", text, moment)

    def _first_false(
        self,
        cond: Condition,
        state: State,
        duration: float | None,
        bindings: Mapping[str, str] | None = None,
    ) -> Condition:
        if isinstance(cond, And):
            for part in cond.operands:
                if not self.ev.holds(part, state, bindings, duration):
                    return self._first_false(part, state, duration, bindings)
        return cond

    def _goal(self, state: State) -> None:
        goal = self.problem.goal
        try:
            if self.ev.holds(goal, state):
                return
            failing = self._first_false(goal, state, None)
        except PlansysBridgeError as exc:
            raise self.fail(None, f"the goal cannot be evaluated: {exc}") from exc
        text = describe(failing, state, self.ev, None)
        raise self.fail(
            None,
            f"the goal is not reached: {text} is false at the end of the plan",
            text,
            self.plan.makespan,
        )
