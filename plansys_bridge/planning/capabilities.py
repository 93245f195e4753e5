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
from collections.abc import Iterable
from typing import Any

from plansys_bridge.pddl.model import (
    Action,
    AddEffect,
    Atom,
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
    Not,
    NumericEffect,
    Or,
    Problem,
    WhenEffect,
)
from plansys_bridge.pddl.walkers import Collector, iter_nodes


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
    if any(type(e) is FluentRef for e in iter_nodes(constraint.value)):
        found.add(Capability.NUMERIC_FLUENTS)


class _Features(Collector):
    """Adds the capability each construct needs; constructs that need none are
    recursed into, and a construct with a ``lower()`` needs what its lowered form
    needs."""

    kinds = ("condition", "effect")

    def __init__(self, found: set[Capability]) -> None:
        self.found = found

    def default(self, node: Any, *args: Any) -> None:
        lower = getattr(node, "lower", None)
        if lower is not None:
            self.walk(lower())
        else:
            super().default(node)

    def walk_atom(self, cond: Atom) -> None:
        return None

    def walk_equals(self, cond: Equals) -> None:
        self.found.add(Capability.EQUALITY)

    def walk_not(self, cond: Not) -> None:
        self.found.add(Capability.NEGATIVE_PRECONDITIONS)
        if type(cond.operand) not in (Atom, Equals):
            self.found.add(Capability.DISJUNCTIVE_PRECONDITIONS)
        self.walk(cond.operand)

    def walk_or(self, cond: Or) -> None:
        self.found.add(Capability.DISJUNCTIVE_PRECONDITIONS)
        super().default(cond)

    def walk_imply(self, cond: Imply) -> None:
        self.found.add(Capability.DISJUNCTIVE_PRECONDITIONS)
        super().default(cond)

    def walk_exists(self, cond: Exists) -> None:
        self.found.add(Capability.EXISTENTIAL_PRECONDITIONS)
        super().default(cond)

    def walk_forall(self, cond: Forall) -> None:
        self.found.add(Capability.UNIVERSAL_PRECONDITIONS)
        super().default(cond)

    def walk_compare(self, cond: Compare) -> None:
        self.found.add(Capability.NUMERIC_FLUENTS)

    def walk_add_effect(self, eff: AddEffect | DeleteEffect) -> None:
        return None

    walk_delete_effect = walk_add_effect

    def walk_numeric_effect(self, eff: NumericEffect) -> None:
        self.found.add(Capability.NUMERIC_FLUENTS)
        if any(type(e) is DurationRef for e in iter_nodes(eff.value)):
            self.found.add(Capability.DURATIVE_ACTIONS)

    def walk_when_effect(self, eff: WhenEffect) -> None:
        self.found.add(Capability.CONDITIONAL_EFFECTS)
        super().default(eff)

    def walk_forall_effect(self, eff: ForallEffect) -> None:
        self.found.add(Capability.CONDITIONAL_EFFECTS)
        super().default(eff)


def _condition(cond: Condition, found: set[Capability]) -> None:
    _Features(found).walk(cond)


def _effect(eff: Effect, found: set[Capability]) -> None:
    _Features(found).walk(eff)


def _has_windows(domain: Domain) -> bool:
    """Some action adds a predicate at start and deletes it at end, and another action
    reads that predicate: a sign that plans need overlapping actions."""
    windows: set[tuple[str, str]] = set()
    for action in domain.actions:
        if isinstance(action, DurativeAction):
            added = {
                e.atom.predicate for e in iter_nodes(action.start_effect) if type(e) is AddEffect
            }
            deleted = {
                e.atom.predicate for e in iter_nodes(action.end_effect) if type(e) is DeleteEffect
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
        read = {a.predicate for c in conds for a in iter_nodes(c) if type(a) is Atom}
        if any(p in read and owner != action.name for p, owner in windows):
            return True
    return False
