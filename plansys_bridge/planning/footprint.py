"""What a happening of a plan reads and writes, and the same for an action with its
parameters still in place.

A :class:`Footprint` is what one happening reads and writes (ground atoms and
fluents): two simultaneous happenings interfere when one changes what the other
touches (:mod:`~plansys_bridge.planning.mutex`). Most actions are conjunctions of
literals, comparisons and plain effects, whose footprint depends on their arguments
only: :func:`lifted_footprint` collects it once per action and instant as a
:class:`LiftedFootprint`, and each happening substitutes its arguments.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from plansys_bridge.knowledge.state import FluentKey
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    Atom,
    Compare,
    Condition,
    DeleteEffect,
    Effect,
    Equals,
    FluentRef,
    Not,
    NumericEffect,
    NumExpr,
)
from plansys_bridge.pddl.walkers import Visitor, iter_nodes

__all__ = ["Args", "Footprint", "LiftedFootprint", "fluent_refs", "lifted_footprint"]

Args = tuple[str, ...]


@dataclass
class Footprint:
    """What one happening reads and writes (ground atoms and fluents)."""

    reads: set[Atom]
    adds: set[Atom]
    deletes: set[Atom]
    fluent_reads: set[FluentKey]
    fluent_writes: set[FluentKey]
    fluent_additive: set[FluentKey] = field(default_factory=set)
    """Written only by ``increase``/``decrease``: commutes with another such write."""

    def interferes(self, other: Footprint) -> str | None:
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


@dataclass(frozen=True)
class LiftedFootprint:
    """A plain action's footprint with its parameters still in place."""

    positive: tuple[tuple[str, Args], ...]
    negative: tuple[tuple[str, Args], ...]
    adds: tuple[tuple[str, Args], ...]
    deletes: tuple[tuple[str, Args], ...]
    fluent_reads: tuple[tuple[str, Args], ...]
    writes: tuple[tuple[str, Args, str], ...]
    """(fluent, arguments, operation) of each numeric effect."""
    literals: bool
    """The condition is a conjunction of literals only: its truth is a set lookup."""

    def ground(self, b: Mapping[str, str]) -> Footprint:
        def sub(args: Args) -> Args:
            return tuple(b.get(a, a) for a in args)

        writes = [((name, sub(args)), op) for name, args, op in self.writes]
        written = {key for key, _op in writes}
        other = {key for key, op in writes if op not in ("increase", "decrease")}
        return Footprint(
            {Atom(p, sub(a)) for p, a in self.positive + self.negative},
            {Atom(p, sub(a)) for p, a in self.adds},
            {Atom(p, sub(a)) for p, a in self.deletes},
            {(f, sub(a)) for f, a in self.fluent_reads},
            written,
            written - other,
        )


class _Collect(Visitor[None]):
    """Gathers a template; ``plain`` turns False at anything whose atoms depend on the
    state (disjunctions, quantifiers, derived predicates, conditional effects)."""

    kinds = ("condition", "effect")

    def __init__(self, derived: set[str]) -> None:
        self.derived = derived
        self.plain = True
        self.literals = True
        self.positive: list[tuple[str, Args]] = []
        self.negative: list[tuple[str, Args]] = []
        self.adds: list[tuple[str, Args]] = []
        self.deletes: list[tuple[str, Args]] = []
        self.fluent_reads: list[tuple[str, Args]] = []
        self.writes: list[tuple[str, Args, str]] = []

    def walk_atom(self, node: Atom, positive: bool = True) -> None:
        if node.predicate in self.derived:
            self.plain = False
        (self.positive if positive else self.negative).append((node.predicate, node.args))

    def walk_not(self, node: Not, positive: bool = True) -> None:
        if not isinstance(node.operand, Atom):
            self.literals = False
        self.walk(node.operand, not positive)

    def walk_and(self, node: And, positive: bool = True) -> None:
        if not positive:
            self.literals = False  # a negated conjunction is a disjunction
        for part in node.operands:
            self.walk(part, positive)

    def walk_compare(self, node: Compare, positive: bool = True) -> None:
        self.literals = False
        self.fluent_reads += fluent_refs(node.left) + fluent_refs(node.right)

    def walk_equals(self, node: Equals, positive: bool = True) -> None:
        self.literals = False

    def _state_dependent(self, node: object, positive: bool = True) -> None:
        self.plain = False

    walk_or = walk_exists = walk_forall = _state_dependent
    walk_when_effect = walk_forall_effect = _state_dependent

    def walk_and_effect(self, node: AndEffect, positive: bool = True) -> None:
        for part in node.effects:
            self.walk(part)

    def walk_add_effect(self, node: AddEffect, positive: bool = True) -> None:
        self.adds.append((node.atom.predicate, node.atom.args))

    def walk_delete_effect(self, node: DeleteEffect, positive: bool = True) -> None:
        self.deletes.append((node.atom.predicate, node.atom.args))

    def walk_numeric_effect(self, node: NumericEffect, positive: bool = True) -> None:
        self.fluent_reads += fluent_refs(node.value)
        self.writes.append((node.fluent.name, node.fluent.args, node.op))

    def template(self) -> LiftedFootprint | None:
        if not self.plain:
            return None
        return LiftedFootprint(
            tuple(self.positive),
            tuple(self.negative),
            tuple(self.adds),
            tuple(self.deletes),
            tuple(self.fluent_reads),
            tuple(self.writes),
            self.literals,
        )


def lifted_footprint(
    condition: Condition, effect: Effect, derived: set[str]
) -> LiftedFootprint | None:
    """What a happening with ``condition`` and ``effect`` touches, its parameters in
    place, or None when that depends on the state (``derived``: derived predicates)."""
    collector = _Collect(derived)
    collector.walk(condition)
    collector.walk(effect)
    return collector.template()


def fluent_refs(expr: NumExpr) -> list[tuple[str, Args]]:
    """The fluents a numeric expression reads, lifted."""
    return [(n.name, n.args) for n in iter_nodes(expr) if isinstance(n, FluentRef)]
