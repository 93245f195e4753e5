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
    TRUE,
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
    ForallEffect,
    Not,
    NumericEffect,
    NumExpr,
    WhenEffect,
    is_variable,
)
from plansys_bridge.pddl.walkers import Collector, Visitor, iter_nodes

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
        self.fluent_reads += _fluent_refs(node.left) + _fluent_refs(node.right)

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
        self.fluent_reads += _fluent_refs(node.value)
        self.writes.append((node.fluent.name, node.fluent.args, node.op))

    def template(self) -> _Template | None:
        if not self.plain:
            return None
        return _Template(
            tuple(self.positive),
            tuple(self.negative),
            tuple(self.adds),
            tuple(self.deletes),
            tuple(self.fluent_reads),
            tuple(self.writes),
            self.literals,
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

    def holds(self, condition: Condition, bindings: Mapping[str, str], state: State) -> bool:
        """True when ``condition`` is a conjunction of literals that holds in ``state``
        (looked up directly); False when it fails or needs the evaluator."""
        template = self._template(condition, NO_EFFECT)
        if template is None or not template.literals:
            return False
        b = bindings
        return all(
            state.has(p, tuple(b.get(x, x) for x in a)) for p, a in template.positive
        ) and not any(state.has(p, tuple(b.get(x, x) for x in a)) for p, a in template.negative)

    def changes(
        self, effect: Effect, bindings: Mapping[str, str]
    ) -> tuple[list[Atom], list[Atom]] | None:
        """(adds, deletes) of an effect of plain adds and deletes; None for anything
        else (numeric, conditional, quantified: the evaluator's work)."""
        template = self._template(TRUE, effect)
        if template is None or template.writes:
            return None
        b = bindings
        return (
            [Atom(p, tuple(b.get(x, x) for x in a)) for p, a in template.adds],
            [Atom(p, tuple(b.get(x, x) for x in a)) for p, a in template.deletes],
        )

    def _template(self, condition: Condition, effect: Effect) -> _Template | None:
        key = (id(condition), id(effect))
        if key not in self._templates:
            collector = _Collect(self._derived)
            collector.walk(condition)
            collector.walk(effect)
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


class _NumericAccesses(Collector):
    """Fluents an effect reads (values on the right of numeric effects, conditions of
    ``when`` parts) and those it changes only additively (``increase``/``decrease``
    and no other kind of assignment). ``forall`` bodies with free variables are left
    to the mutex check on what they write, which then counts as not additive."""

    kinds = ("effect",)

    def __init__(self, ev: Evaluator, bindings: Mapping[str, str], state: State) -> None:
        self.ev = ev
        self.bindings = bindings
        self.state = state
        self.reads: set[FluentKey] = set()
        self.additive: set[FluentKey] = set()
        self.other: set[FluentKey] = set()

    def _ground(self, args: Args) -> Args | None:
        out = tuple(self.bindings.get(a, a) for a in args)
        return None if any(is_variable(a) for a in out) else out

    def walk_when_effect(self, node: WhenEffect) -> None:
        self.reads.update(self.ev.condition_fluents(node.condition, self.bindings, self.state))
        self.walk(node.effect)

    def walk_forall_effect(self, node: ForallEffect) -> None:
        return None

    def walk_add_effect(self, node: AddEffect) -> None:
        return None

    walk_delete_effect = walk_add_effect

    def walk_numeric_effect(self, node: NumericEffect) -> None:
        for name, args in _fluent_refs(node.value):
            grounded = self._ground(args)
            if grounded is not None:
                self.reads.add((name, grounded))
        target = self._ground(node.fluent.args)
        if target is not None:
            key = (node.fluent.name, target)
            (self.additive if node.op in ("increase", "decrease") else self.other).add(key)


def _numeric_accesses(
    ev: Evaluator, effect: Effect, bindings: Mapping[str, str], state: State
) -> tuple[set[FluentKey], set[FluentKey]]:
    """(fluents read, fluents changed only additively): see :class:`_NumericAccesses`."""
    walker = _NumericAccesses(ev, bindings, state)
    walker.walk(effect)
    return walker.reads, walker.additive - walker.other


def _fluent_refs(expr: NumExpr) -> list[tuple[str, Args]]:
    return [(n.name, n.args) for n in iter_nodes(expr) if isinstance(n, FluentRef)]
