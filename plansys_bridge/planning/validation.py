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
condition, with numeric values where they explain the failure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Literal

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    And,
    AndEffect,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    Domain,
    DurativeAction,
    Effect,
    FluentRef,
    Negate,
    NumericEffect,
    NumExpr,
    Problem,
    WhenEffect,
    is_variable,
)
from plansys_bridge.planning.plan import Plan, PlanStep

__all__ = ["DEFAULT_EPSILON", "ValidationReport", "initial_state", "validate_plan"]

DEFAULT_EPSILON = 0.001
SAME_TIME = 1e-6
"""Happenings closer than this are simultaneous (plan files print 3-4 decimals)."""
_SLACK = 1e-6

Point = Literal["start", "end", "instant"]


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


@dataclass
class _Happening:
    time: float
    index: int
    point: Point
    ground: GroundAction
    duration: float | None

    @property
    def condition(self) -> Condition:
        g = self.ground
        if self.point == "start":
            return g.at_start
        if self.point == "end":
            return g.at_end
        return g.over_all

    @property
    def when(self) -> str:
        return {
            "start": "at start condition",
            "end": "at end condition",
            "instant": "precondition",
        }[self.point]

    @property
    def effect(self) -> Effect:
        return self.ground.start_effect if self.point == "start" else self.ground.end_effect

    def sort_key(self) -> tuple[float, int, int]:
        # ends before starts at one time: an interval closes before the next opens
        order = {"end": 0, "instant": 1, "start": 2}[self.point]
        return (self.time, order, self.index)


@dataclass
class _Footprint:
    """What one happening reads and writes (ground atoms and fluents)."""

    reads: set[Atom]
    adds: set[Atom]
    deletes: set[Atom]
    fluent_reads: set[FluentKey]
    fluent_writes: set[FluentKey]
    fluent_additive: set[FluentKey] = field(default_factory=set)
    """Written only by ``increase``/``decrease``: commutes with another such write."""

    def interferes(self, other: _Footprint) -> str | None:
        """The shared atom or fluent that makes the two interfere, or None."""
        for mine, theirs in (
            (self.adds, other.deletes),
            (self.deletes, other.adds),
            (self.adds | self.deletes, other.reads),
            (other.adds | other.deletes, self.reads),
        ):
            common = mine & theirs
            if common:
                return str(sorted(common, key=str)[0])
        # PDDL 2.1 (Fox & Long 2003, section 8): a fluent one changes must not be read
        # by the other (conditions, right-hand sides), and both may change it only if
        # both do so additively (increase/decrease commute).
        both_additive = self.fluent_additive & other.fluent_additive
        for fcommon in (
            self.fluent_writes & other.fluent_reads,
            other.fluent_writes & self.fluent_reads,
            (self.fluent_writes & other.fluent_writes) - both_additive,
        ):
            if fcommon:
                name, args = sorted(fcommon)[0]
                return "(" + " ".join((name, *args)) + ")"
        return None


class _Prints:
    """The footprints of one group of simultaneous happenings, worked out on first use:
    only simultaneous steps and happenings closer than epsilon are compared, and
    computing every footprint was most of a validation's time."""

    def __init__(self, validator: _Validator, group: list[_Happening], state: State) -> None:
        self._validator = validator
        self._group = group
        self._state = state
        self._prints: list[tuple[_Happening, _Footprint]] | None = None

    def get(self) -> list[tuple[_Happening, _Footprint]]:
        if self._prints is None:
            footprint = self._validator._footprint
            self._prints = [(h, footprint(h, self._state)) for h in self._group]
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
        open_steps: dict[int, _Happening] = {}
        recent: list[tuple[float, _Prints]] = []
        position = 0
        while position < len(happenings):
            group = [happenings[position]]
            position += 1
            while (
                position < len(happenings)
                and happenings[position].time - group[0].time <= SAME_TIME
            ):
                group.append(happenings[position])
                position += 1
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

    def _happenings(self) -> list[_Happening]:
        out: list[_Happening] = []
        for i, step in enumerate(self.plan.steps):
            if not math.isfinite(step.time) or step.time < 0:
                raise self.fail(i, f"start time {step.time} is not a time >= 0")
            try:
                g = self.ev.ground_action(step.action, step.arguments, self.state)
            except PlansysBridgeError as exc:
                raise self.fail(i, str(exc)) from exc
            if isinstance(g.action, DurativeAction):
                if not math.isfinite(step.duration) or step.duration < 0:
                    raise self.fail(i, f"duration {step.duration} is not a duration >= 0")
                out.append(_Happening(step.time, i, "start", g, step.duration))
                out.append(_Happening(step.time + step.duration, i, "end", g, step.duration))
            else:
                out.append(_Happening(step.time, i, "instant", g, None))
        out.sort(key=_Happening.sort_key)
        return out

    def _group(
        self,
        group: list[_Happening],
        state: State,
        open_steps: dict[int, _Happening],
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
        for h in group:
            try:
                state = self.ev.apply(h.effect, state, {}, h.duration)
            except PlansysBridgeError as exc:
                raise self.fail(
                    h.index, f"{h.point} effect cannot be applied: {exc}", None, now
                ) from exc
        for h in group:
            if h.point == "start":
                open_steps[h.index] = h
            elif h.point == "end":
                open_steps.pop(h.index, None)
        for index in sorted(open_steps):
            h = open_steps[index]
            end = h.time + (h.duration or 0.0)
            if end - now > SAME_TIME:
                self._check(h, h.ground.over_all, "over all condition", state, now)
        return state

    def _explain_simultaneous(
        self, exc: _Invalid, h: _Happening, prints: list[tuple[_Happening, _Footprint]]
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

    def _check_duration(self, h: _Happening, state: State) -> None:
        action = h.ground.action
        if not isinstance(action, DurativeAction) or h.duration is None:
            return
        for constraint in action.duration:
            try:
                value = self.ev.value(constraint.value, state, h.ground.bindings)
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
        h: _Happening,
        cond: Condition,
        when: str,
        state: State,
        time: float | None = None,
    ) -> None:
        try:
            if self.ev.holds(cond, state, {}, h.duration):
                return
            failing = self._first_false(cond, state, h.duration)
        except PlansysBridgeError as exc:
            raise self.fail(
                h.index,
                f"{when} cannot be evaluated: {exc}",
                None,
                time if time is not None else h.time,
            ) from exc
        text = _describe(failing, state, self.ev, h.duration)
        moment = time if time is not None else h.time
        suffix = f" at {_t(moment)}" if when.startswith("over all") else ""
        raise self.fail(h.index, f"{when} {text} is false{suffix}", text, moment)

    def _first_false(self, cond: Condition, state: State, duration: float | None) -> Condition:
        if isinstance(cond, And):
            for part in cond.operands:
                if not self.ev.holds(part, state, {}, duration):
                    return self._first_false(part, state, duration)
        return cond

    def _footprint(self, h: _Happening, state: State) -> _Footprint:
        cond = h.condition
        pos, neg = self.ev.condition_atoms(cond, {}, state)
        adds, deletes, written = self.ev.effect_atoms(h.effect, {}, state)
        effect_reads, additive = _numeric_accesses(self.ev, h.effect, state)
        return _Footprint(
            pos | neg,
            adds,
            deletes,
            self.ev.condition_fluents(cond, {}, state) | effect_reads,
            written,
            additive & written,
        )

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


def _numeric_accesses(
    ev: Evaluator, effect: Effect, state: State
) -> tuple[set[FluentKey], set[FluentKey]]:
    """Fluents an effect reads (values on the right of numeric effects, conditions of
    ``when`` parts) and those it changes only additively (``increase``/``decrease``
    and no other kind of assignment). ``forall`` bodies with free variables are left
    to the mutex check on what they write, which then counts as not additive."""
    reads: set[FluentKey] = set()
    additive: set[FluentKey] = set()
    other: set[FluentKey] = set()

    def visit(eff: Effect) -> None:
        if isinstance(eff, AndEffect):
            for sub in eff.effects:
                visit(sub)
        elif isinstance(eff, WhenEffect):
            reads.update(ev.condition_fluents(eff.condition, {}, state))
            visit(eff.effect)
        elif isinstance(eff, NumericEffect):
            reads.update(
                (ref.name, ref.args)
                for ref in _fluent_refs(eff.value)
                if not any(is_variable(a) for a in ref.args)
            )
            if not any(is_variable(a) for a in eff.fluent.args):
                key = (eff.fluent.name, eff.fluent.args)
                (additive if eff.op in ("increase", "decrease") else other).add(key)

    visit(effect)
    return reads, additive - other


def _fluent_refs(expr: NumExpr) -> list[FluentRef]:
    if isinstance(expr, FluentRef):
        return [expr]
    if isinstance(expr, BinaryOp):
        return _fluent_refs(expr.left) + _fluent_refs(expr.right)
    if isinstance(expr, Negate):
        return _fluent_refs(expr.operand)
    return []


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
