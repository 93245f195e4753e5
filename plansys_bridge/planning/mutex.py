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

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.plan_atoms import AtomWalker
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    NO_EFFECT,
    TRUE,
    AddEffect,
    Atom,
    Condition,
    Effect,
    ForallEffect,
    NumericEffect,
    WhenEffect,
    is_variable,
)
from plansys_bridge.pddl.walkers import Collector
from plansys_bridge.planning.footprint import (
    Args,
    Footprint,
    LiftedFootprint,
    fluent_refs,
    lifted_footprint,
)
from plansys_bridge.planning.ground_parts import CompiledParts, GroundParts, interference

__all__ = ["CompiledParts", "Footprint", "Footprints", "GroundParts", "interference"]


class Footprints:
    """Footprints of happenings, by their lifted condition and effect and bindings."""

    def __init__(self, ev: Evaluator) -> None:
        self.ev = ev
        self._derived = {rule.head.name for rule in ev.domain.derived}
        self._templates: dict[tuple[int, int], LiftedFootprint | None] = {}
        self._compiled: dict[tuple[int, Args], CompiledParts] = {}

    def of(
        self, condition: Condition, effect: Effect, bindings: Mapping[str, str], state: State
    ) -> Footprint:
        template = self._template(condition, effect)
        if template is not None:
            return template.ground(bindings)
        return self._asked(condition, effect, dict(bindings), state)

    def parts(
        self, condition: Condition, effect: Effect, bindings: Mapping[str, str]
    ) -> GroundParts | None:
        """The happening's parts with its arguments in place, or None when what it
        reads or writes depends on the state (then :meth:`of` asks the evaluator)."""
        compiled = self.compiled(condition, effect, tuple(bindings))
        return None if compiled is None else compiled.ground(tuple(bindings.values()), bindings)

    def compiled(self, condition: Condition, effect: Effect, names: Args) -> CompiledParts | None:
        """What grounds the parts of a happening whose parameters are ``names``, or None
        when what it touches depends on the state."""
        template = self._template(condition, effect)
        if template is None:
            return None
        key = (id(template), names)
        compiled = self._compiled.get(key)
        if compiled is None:
            compiled = self._compiled[key] = CompiledParts(template, names)
        return compiled

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

    def _template(self, condition: Condition, effect: Effect) -> LiftedFootprint | None:
        key = (id(condition), id(effect))
        if key not in self._templates:
            self._templates[key] = lifted_footprint(condition, effect, self._derived)
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
        for name, args in fluent_refs(node.value):
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
