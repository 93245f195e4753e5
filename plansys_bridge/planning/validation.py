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
worked out by :mod:`~plansys_bridge.planning.mutex`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.grounding import substitute_condition
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    And,
    Atom,
    Compare,
    Condition,
    Domain,
    DurativeAction,
    Problem,
)
from plansys_bridge.planning.happenings import SAME_TIME, BoundStep, Happening, simultaneous
from plansys_bridge.planning.mutex import Footprint, Footprints
from plansys_bridge.planning.plan import Plan, PlanStep

__all__ = ["DEFAULT_EPSILON", "ValidationReport", "initial_state", "validate_plan"]

DEFAULT_EPSILON = 0.001
_SLACK = 1e-6


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


class _Prints:
    """The footprints of one group of simultaneous happenings, worked out on first use:
    only simultaneous steps and happenings closer than epsilon are compared, and
    computing every footprint was most of a validation's time."""

    def __init__(self, validator: _Validator, group: list[Happening], state: State) -> None:
        self._validator = validator
        self._group = group
        self._state = state
        self._prints: list[tuple[Happening, Footprint]] | None = None

    def get(self) -> list[tuple[Happening, Footprint]]:
        if self._prints is None:
            footprints = self._validator.footprints
            self._prints = [
                (h, footprints.of(h.condition, h.effect, h.bindings, self._state))
                for h in self._group
            ]
        return self._prints


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
        self._over_all_reads: dict[int, tuple[set[Atom], set[FluentKey]] | None] = {}
        self.state = state if state is not None else initial_state(domain, problem)
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
            where = f"step {index + 1} {step.text} at {_t(step.time)}: "
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
        happenings = self._happenings()
        state = self.state
        open_steps: dict[int, Happening] = {}
        recent: list[tuple[float, _Prints]] = []
        for group in simultaneous(happenings):
            state = self._group(group, state, open_steps, recent)
        for h in open_steps.values():  # only reachable with inconsistent input
            raise self.fail(h.index, "never ends")
        self._goal(state)
        return ValidationReport(
            True,
            f"plan valid: {len(self.plan)} steps, makespan {self.plan.makespan:.3f}",
            makespan=self.plan.makespan,
            final_state=state,
        )

    def _happenings(self) -> list[Happening]:
        out: list[Happening] = []
        for i, step in enumerate(self.plan.steps):
            if not math.isfinite(step.time) or step.time < 0:
                raise self.fail(i, f"start time {step.time} is not a time >= 0")
            try:
                action, bindings = self.ev.bind(step.action, step.arguments, self.state)
            except PlansysBridgeError as exc:
                raise self.fail(i, str(exc)) from exc
            g = BoundStep(action, bindings)
            if isinstance(action, DurativeAction):
                if not math.isfinite(step.duration) or step.duration < 0:
                    raise self.fail(i, f"duration {step.duration} is not a duration >= 0")
                out.append(Happening(step.time, i, "start", g, step.duration))
                out.append(Happening(step.time + step.duration, i, "end", g, step.duration))
            else:
                out.append(Happening(step.time, i, "instant", g, None))
        out.sort(key=Happening.sort_key)
        return out

    def _group(
        self,
        group: list[Happening],
        state: State,
        open_steps: dict[int, Happening],
        recent: list[tuple[float, _Prints]],
    ) -> State:
        now = group[0].time
        prints = _Prints(self, group, state)
        for h in group:
            if h.point == "start":
                self._check_duration(h, state)
            try:
                self._check(h, h.condition, h.when, state)
            except _Invalid as exc:
                raise self._explain_simultaneous(exc, h, prints.get()) from None
        pairs = prints.get() if len({h.index for h in group}) > 1 else []
        for a in range(len(pairs)):
            for b in range(a + 1, len(pairs)):
                ha, fa = pairs[a]
                hb, fb = pairs[b]
                if ha.index == hb.index:
                    continue
                shared = fa.interferes(fb)
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
        changed: set[object] = set()
        for h in group:
            quick = self.footprints.changes(h.effect, h.bindings)
            try:
                adds, deletes, values = (
                    (*quick, {})
                    if quick is not None
                    else self.ev.changes(h.effect, state, h.bindings, h.duration)
                )
            except PlansysBridgeError as exc:
                raise self.fail(
                    h.index, f"{h.point} effect cannot be applied: {exc}", None, now
                ) from exc
            state = state.with_changes(adds=adds, deletes=deletes, fluents=values)
            changed.update(adds, deletes, values)
        started = set()
        for h in group:
            if h.point == "start":
                open_steps[h.index] = h
                started.add(h.index)
            elif h.point == "end":
                open_steps.pop(h.index, None)
        for index in sorted(open_steps):
            h = open_steps[index]
            end = h.time + (h.duration or 0.0)
            if end - now > SAME_TIME and (index in started or self._touched(h, changed)):
                self._check(h, h.bound.over_all, "over all condition", state, now)
        return state

    def _touched(self, h: Happening, changed: set[object]) -> bool:
        """Could the changes of this group have made ``h``'s over-all condition false?

        It held after its start and at every later change; what does not change what
        it reads leaves it true.
        """
        if not changed:
            return False
        if h.index not in self._over_all_reads:
            self._over_all_reads[h.index] = self.footprints.reads(h.bound.over_all, h.bindings)
        reads = self._over_all_reads[h.index]
        if reads is None:
            return True
        atoms, fluents = reads
        return not (changed.isdisjoint(atoms) and changed.isdisjoint(fluents))

    def _explain_simultaneous(
        self, exc: _Invalid, h: Happening, prints: list[tuple[Happening, Footprint]]
    ) -> _Invalid:
        """A condition false only because its achiever happens at the same time: say so."""
        failing = exc.report.failing_condition
        for other, footprint in prints:
            if other.index == h.index or failing is None:
                continue
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
                    shared = fa.interferes(fb)
                    if shared is not None:
                        other = self.plan.steps[ha.index]
                        raise self.fail(
                            hb.index,
                            f"its {hb.point} is only {_t(now - then)} after the {ha.point} of "
                            f"step {ha.index + 1} {other.text} and both touch {shared} "
                            f"(happenings that interfere must be {self.epsilon:g} apart)",
                            shared,
                            now,
                        )
        recent.append((now, prints))

    def _check_duration(self, h: Happening, state: State) -> None:
        action = h.bound.action
        if not isinstance(action, DurativeAction) or h.duration is None:
            return
        for constraint in action.duration:
            try:
                value = self.ev.value(constraint.value, state, h.bindings)
            except PlansysBridgeError as exc:
                raise self.fail(
                    h.index, f"duration cannot be evaluated: {exc}", None, h.time
                ) from exc
            tol = self.duration_tolerance
            ok = {
                "=": abs(h.duration - value) <= tol,
                "<=": h.duration <= value + tol,
                ">=": h.duration >= value - tol,
            }[constraint.op]
            if not ok:
                text = f"(?duration {constraint.op} {value:g})"
                raise self.fail(
                    h.index,
                    f"duration {h.duration:g} does not satisfy {constraint.op} {value:g}",
                    text,
                    h.time,
                )

    def _check(
        self,
        h: Happening,
        cond: Condition,
        when: str,
        state: State,
        time: float | None = None,
    ) -> None:
        if self.footprints.holds(cond, h.bindings, state):
            return  # a conjunction of literals, looked up directly
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
        text = _describe(substitute_condition(failing, h.bindings), state, self.ev, h.duration)
        moment = time if time is not None else h.time
        suffix = f" at {_t(moment)}" if when.startswith("over all") else ""
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
        text = _describe(failing, state, self.ev, None)
        raise self.fail(
            None,
            f"the goal is not reached: {text} is false at the end of the plan",
            text,
            self.plan.makespan,
        )


def _describe(cond: Condition, state: State, ev: Evaluator, duration: float | None) -> str:
    text = _condition_text(cond)
    if isinstance(cond, Compare):
        try:
            left = ev.value(cond.left, state, {}, duration)
            right = ev.value(cond.right, state, {}, duration)
        except PlansysBridgeError:
            return text
        return f"{text} [{left:g} {cond.op} {right:g}]"
    return text


def _condition_text(cond: Condition) -> str:
    try:
        from plansys_bridge.pddl.writer import write_condition
    except ImportError:
        return str(cond) if isinstance(cond, Atom) else repr(cond)
    return write_condition(cond)


def _t(time: float) -> str:
    """A plan time as plan files print it, without trailing zeros: ``5.0005``, ``10``."""
    return f"{time:.6f}".rstrip("0").rstrip(".")
