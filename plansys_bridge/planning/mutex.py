"""Which simultaneous happenings of a plan interfere (PDDL 2.1 mutex).

Two happenings at the same time (or closer than epsilon) must not interfere: no
effect of one may touch what the other reads or changes (Fox & Long 2003, section
8), except that additive changes of one numeric fluent (``increase`` /
``decrease``) commute. A :class:`Footprint` is what one happening reads and writes;
:class:`Footprints` works them out for the plan validator.

Most actions are conjunctions of literals, comparisons and plain effects: what they
touch then depends on their arguments only. For those, the lifted atoms are
collected once per action and instant and each happening only substitutes its
arguments; anything else (quantifiers, disjunctions, derived predicates,
conditional effects) is asked of the evaluator in the state of the happening.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.plan_atoms import AtomWalker
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    NO_EFFECT,
    AddEffect,
    And,
    AndEffect,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DeleteEffect,
    Effect,
    Equals,
    FluentRef,
    Negate,
    Not,
    NumericEffect,
    NumExpr,
    WhenEffect,
    is_variable,
)

__all__ = ["Footprint", "Footprints"]

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
class _Template:
    """A plain action's footprint with its parameters still in place."""

    reads: tuple[tuple[str, Args], ...]
    adds: tuple[tuple[str, Args], ...]
    deletes: tuple[tuple[str, Args], ...]
    fluent_reads: tuple[tuple[str, Args], ...]
    writes: tuple[tuple[str, Args, str], ...]
    """(fluent, arguments, operation) of each numeric effect."""

    def ground(self, b: Mapping[str, str]) -> Footprint:
        def sub(args: Args) -> Args:
            return tuple(b.get(a, a) for a in args)

        writes = [((name, sub(args)), op) for name, args, op in self.writes]
        written = {key for key, _op in writes}
        other = {key for key, op in writes if op not in ("increase", "decrease")}
        return Footprint(
            {Atom(p, sub(a)) for p, a in self.reads},
            {Atom(p, sub(a)) for p, a in self.adds},
            {Atom(p, sub(a)) for p, a in self.deletes},
            {(f, sub(a)) for f, a in self.fluent_reads},
            written,
            written - other,
        )


class _Collector:
    """Gathers a template; ``plain`` turns False at anything that needs a state."""

    def __init__(self, derived: set[str]) -> None:
        self.derived = derived
        self.plain = True
        self.reads: list[tuple[str, Args]] = []
        self.adds: list[tuple[str, Args]] = []
        self.deletes: list[tuple[str, Args]] = []
        self.fluent_reads: list[tuple[str, Args]] = []
        self.writes: list[tuple[str, Args, str]] = []

    def condition(self, cond: Condition) -> None:
        if isinstance(cond, Atom):
            if cond.predicate in self.derived:
                self.plain = False
            self.reads.append((cond.predicate, cond.args))
        elif isinstance(cond, Not):
            self.condition(cond.operand)
        elif isinstance(cond, And):
            for part in cond.operands:
                self.condition(part)
        elif isinstance(cond, Compare):
            self.fluent_reads += _fluent_refs(cond.left) + _fluent_refs(cond.right)
        elif not isinstance(cond, Equals):
            self.plain = False  # Or, Imply, Exists, Forall

    def effect(self, eff: Effect) -> None:
        if isinstance(eff, AndEffect):
            for part in eff.effects:
                self.effect(part)
        elif isinstance(eff, AddEffect):
            self.adds.append((eff.atom.predicate, eff.atom.args))
        elif isinstance(eff, DeleteEffect):
            self.deletes.append((eff.atom.predicate, eff.atom.args))
        elif isinstance(eff, NumericEffect):
            self.fluent_reads += _fluent_refs(eff.value)
            self.writes.append((eff.fluent.name, eff.fluent.args, eff.op))
        else:
            self.plain = False  # WhenEffect, ForallEffect

    def template(self) -> _Template | None:
        if not self.plain:
            return None
        return _Template(
            tuple(self.reads),
            tuple(self.adds),
            tuple(self.deletes),
            tuple(self.fluent_reads),
            tuple(self.writes),
        )


class Footprints:
    """Footprints of happenings, by their lifted condition and effect and bindings."""

    def __init__(self, ev: Evaluator) -> None:
        self.ev = ev
        self._derived = {rule.head.name for rule in ev.domain.derived}
        self._templates: dict[tuple[int, int], _Template | None] = {}

    def of(
        self, condition: Condition, effect: Effect, bindings: Mapping[str, str], state: State
    ) -> Footprint:
        template = self._template(condition, effect)
        if template is not None:
            return template.ground(bindings)
        return self._asked(condition, effect, dict(bindings), state)

    def reads(
        self, condition: Condition, bindings: Mapping[str, str]
    ) -> tuple[set[Atom], set[FluentKey]] | None:
        """The atoms and fluents ``condition`` reads whatever the state, or None when
        that depends on the state (quantifiers, disjunctions, derived predicates)."""
        template = self._template(condition, NO_EFFECT)
        if template is None:
            return None
        footprint = template.ground(bindings)
        return footprint.reads, footprint.fluent_reads

    def _template(self, condition: Condition, effect: Effect) -> _Template | None:
        key = (id(condition), id(effect))
        if key not in self._templates:
            collector = _Collector(self._derived)
            collector.condition(condition)
            collector.effect(effect)
            self._templates[key] = collector.template()
        return self._templates[key]

    def _asked(
        self, condition: Condition, effect: Effect, bindings: dict[str, str], state: State
    ) -> Footprint:
        walker = AtomWalker(self.ev, state)
        walker.walk(condition, bindings, True)
        adds, deletes, written = self.ev.effect_atoms(effect, bindings, state)
        effect_reads, additive = _numeric_accesses(self.ev, effect, bindings, state)
        return Footprint(
            walker.positive | walker.negative,
            adds,
            deletes,
            walker.fluents | effect_reads,
            written,
            additive & written,
        )


def _numeric_accesses(
    ev: Evaluator, effect: Effect, bindings: Mapping[str, str], state: State
) -> tuple[set[FluentKey], set[FluentKey]]:
    """Fluents an effect reads (values on the right of numeric effects, conditions of
    ``when`` parts) and those it changes only additively (``increase``/``decrease``
    and no other kind of assignment). ``forall`` bodies with free variables are left
    to the mutex check on what they write, which then counts as not additive."""
    reads: set[FluentKey] = set()
    additive: set[FluentKey] = set()
    other: set[FluentKey] = set()

    def ground(args: Args) -> Args | None:
        out = tuple(bindings.get(a, a) for a in args)
        return None if any(is_variable(a) for a in out) else out

    def visit(eff: Effect) -> None:
        if isinstance(eff, AndEffect):
            for sub in eff.effects:
                visit(sub)
        elif isinstance(eff, WhenEffect):
            reads.update(ev.condition_fluents(eff.condition, bindings, state))
            visit(eff.effect)
        elif isinstance(eff, NumericEffect):
            for name, args in _fluent_refs(eff.value):
                grounded = ground(args)
                if grounded is not None:
                    reads.add((name, grounded))
            target = ground(eff.fluent.args)
            if target is not None:
                key = (eff.fluent.name, target)
                (additive if eff.op in ("increase", "decrease") else other).add(key)

    visit(effect)
    return reads, additive - other


def _fluent_refs(expr: NumExpr) -> list[tuple[str, Args]]:
    if isinstance(expr, FluentRef):
        return [(expr.name, expr.args)]
    if isinstance(expr, BinaryOp):
        return _fluent_refs(expr.left) + _fluent_refs(expr.right)
    if isinstance(expr, Negate):
        return _fluent_refs(expr.operand)
    return []
