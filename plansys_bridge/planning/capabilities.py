"""What a planning task needs from a solver, read off the model itself.

Solvers declare the PDDL features they plan with; the planner computes the
features a domain and problem actually use and picks a solver whose declaration
covers them. The features are found by walking the model rather than trusting the
``:requirements`` line, because PlanSys2's domains often under-declare (a domain
using ``not`` without ``:negative-preconditions`` is common) and a solver given a
feature it does not know fails late and obscurely.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Iterator

from plansys_bridge.pddl.model import (
    Action,
    AddEffect,
    And,
    AndEffect,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DeleteEffect,
    Domain,
    DurationConstraint,
    DurationRef,
    DurativeAction,
    Effect,
    Equals,
    Exists,
    FluentRef,
    Forall,
    ForallEffect,
    Imply,
    Negate,
    Not,
    NumericEffect,
    NumExpr,
    Or,
    Problem,
    WhenEffect,
)


class Capability(enum.Enum):
    """A PDDL feature a solver may or may not plan with (names as PDDL requirements)."""

    DURATIVE_ACTIONS = "durative-actions"
    DURATION_INEQUALITIES = "duration-inequalities"
    NUMERIC_FLUENTS = "numeric-fluents"
    NEGATIVE_PRECONDITIONS = "negative-preconditions"
    DISJUNCTIVE_PRECONDITIONS = "disjunctive-preconditions"
    EXISTENTIAL_PRECONDITIONS = "existential-preconditions"
    UNIVERSAL_PRECONDITIONS = "universal-preconditions"
    CONDITIONAL_EFFECTS = "conditional-effects"
    EQUALITY = "equality"
    DERIVED_PREDICATES = "derived-predicates"
    REQUIRED_CONCURRENCY = "required-concurrency"
    """Not a PDDL requirement: an action opens a window (adds a fact at start, deletes
    it at end) that another action needs, so the two must overlap (PlanSys2's
    match/fuse). LPG-td and TFD cannot plan that."""

    def __str__(self) -> str:
        return f":{self.value}"


ALL_CAPABILITIES: frozenset[Capability] = frozenset(Capability)


def describe(caps: Iterable[Capability]) -> str:
    """``:durative-actions :numeric-fluents`` in a stable order, for messages."""
    return " ".join(str(c) for c in sorted(caps, key=lambda c: c.value)) or "(none)"


def required_capabilities(domain: Domain, problem: Problem | None = None) -> frozenset[Capability]:
    """The features the domain's actions and the problem's goal actually use."""
    found: set[Capability] = set()
    for action in domain.actions:
        if isinstance(action, DurativeAction):
            found.add(Capability.DURATIVE_ACTIONS)
            for constraint in action.duration:
                _duration(constraint, found)
            for cond in (action.at_start, action.over_all, action.at_end):
                _condition(cond, found)
            for eff in (action.start_effect, action.end_effect):
                _effect(eff, found)
        elif isinstance(action, Action):
            _condition(action.precondition, found)
            _effect(action.effect, found)
    for derived in domain.derived:
        found.add(Capability.DERIVED_PREDICATES)
        _condition(derived.condition, found)
    if _has_windows(domain):
        found.add(Capability.REQUIRED_CONCURRENCY)
    if problem is not None:
        _condition(problem.goal, found)
    return frozenset(found)


def _duration(constraint: DurationConstraint, found: set[Capability]) -> None:
    if constraint.op != "=":
        found.add(Capability.DURATION_INEQUALITIES)
    if any(isinstance(e, FluentRef) for e in _num_nodes(constraint.value)):
        found.add(Capability.NUMERIC_FLUENTS)


def _num_nodes(expr: NumExpr) -> Iterator[NumExpr]:
    yield expr
    if isinstance(expr, BinaryOp):
        yield from _num_nodes(expr.left)
        yield from _num_nodes(expr.right)
    elif isinstance(expr, Negate):
        yield from _num_nodes(expr.operand)


def _condition(cond: Condition, found: set[Capability]) -> None:
    if isinstance(cond, Atom):
        return
    if isinstance(cond, Equals):
        found.add(Capability.EQUALITY)
    elif isinstance(cond, Not):
        found.add(Capability.NEGATIVE_PRECONDITIONS)
        if not isinstance(cond.operand, Atom | Equals):
            found.add(Capability.DISJUNCTIVE_PRECONDITIONS)
        _condition(cond.operand, found)
    elif isinstance(cond, And):
        for op in cond.operands:
            _condition(op, found)
    elif isinstance(cond, Or):
        found.add(Capability.DISJUNCTIVE_PRECONDITIONS)
        for op in cond.operands:
            _condition(op, found)
    elif isinstance(cond, Imply):
        found.add(Capability.DISJUNCTIVE_PRECONDITIONS)
        _condition(cond.antecedent, found)
        _condition(cond.consequent, found)
    elif isinstance(cond, Exists):
        found.add(Capability.EXISTENTIAL_PRECONDITIONS)
        _condition(cond.body, found)
    elif isinstance(cond, Forall):
        found.add(Capability.UNIVERSAL_PRECONDITIONS)
        _condition(cond.body, found)
    elif isinstance(cond, Compare):
        found.add(Capability.NUMERIC_FLUENTS)


def _effect(eff: Effect, found: set[Capability]) -> None:
    if isinstance(eff, AddEffect | DeleteEffect):
        return
    if isinstance(eff, NumericEffect):
        found.add(Capability.NUMERIC_FLUENTS)
        if any(isinstance(e, DurationRef) for e in _num_nodes(eff.value)):
            found.add(Capability.DURATIVE_ACTIONS)
    elif isinstance(eff, AndEffect):
        for sub in eff.effects:
            _effect(sub, found)
    elif isinstance(eff, WhenEffect):
        found.add(Capability.CONDITIONAL_EFFECTS)
        _condition(eff.condition, found)
        _effect(eff.effect, found)
    elif isinstance(eff, ForallEffect):
        found.add(Capability.CONDITIONAL_EFFECTS)
        _effect(eff.effect, found)


def _has_windows(domain: Domain) -> bool:
    """Some action adds a predicate at start and deletes it at end, and another action
    reads that predicate: a sign that plans need overlapping actions."""
    windows: set[tuple[str, str]] = set()
    for action in domain.actions:
        if isinstance(action, DurativeAction):
            added = {
                e.atom.predicate
                for e in _leaf_effects(action.start_effect)
                if isinstance(e, AddEffect)
            }
            deleted = {
                e.atom.predicate
                for e in _leaf_effects(action.end_effect)
                if isinstance(e, DeleteEffect)
            }
            windows |= {(p, action.name) for p in added & deleted}
    if not windows:
        return False
    for action in domain.actions:
        conds = (
            (action.at_start, action.over_all, action.at_end)
            if isinstance(action, DurativeAction)
            else (action.precondition,)
        )
        read = {a.predicate for c in conds for a in _atoms(c)}
        if any(p in read and owner != action.name for p, owner in windows):
            return True
    return False


def _leaf_effects(eff: Effect) -> Iterator[Effect]:
    if isinstance(eff, AndEffect):
        for sub in eff.effects:
            yield from _leaf_effects(sub)
    elif isinstance(eff, WhenEffect | ForallEffect):
        yield from _leaf_effects(eff.effect)
    else:
        yield eff


def _atoms(cond: Condition) -> Iterator[Atom]:
    if isinstance(cond, Atom):
        yield cond
    elif isinstance(cond, And | Or):
        for op in cond.operands:
            yield from _atoms(op)
    elif isinstance(cond, Not):
        yield from _atoms(cond.operand)
    elif isinstance(cond, Imply):
        yield from _atoms(cond.antecedent)
        yield from _atoms(cond.consequent)
    elif isinstance(cond, Exists | Forall):
        yield from _atoms(cond.body)
