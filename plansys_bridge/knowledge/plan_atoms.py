"""Which ground atoms and fluents a condition needs and an effect changes.

The executor's plan graph links a step that needs an atom to the step that makes it
true (and orders steps whose effects would break another's requirement), so it asks
these questions for every step; the evaluator's ``condition_atoms``,
``condition_fluents`` and ``effect_atoms`` methods delegate here.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.grounding import ground_args
from plansys_bridge.knowledge.reasoner import Reasoner
from plansys_bridge.knowledge.state import Args, FluentKey, State
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
    Exists,
    FluentRef,
    Forall,
    ForallEffect,
    Not,
    NumericEffect,
    Or,
    WhenEffect,
)
from plansys_bridge.pddl.walkers import Visitor, children

__all__ = ["AtomWalker", "effect_atoms"]

Bindings = Mapping[str, str]


class _EffectAtoms(Visitor[None]):
    """(adds, deletes, numeric fluent keys); see :meth:`Evaluator.effect_atoms`."""

    kinds = ("effect",)

    def __init__(self, reasoner: Reasoner, state: State | None) -> None:
        self.r = reasoner
        self.check = state is not None
        self.ctx = reasoner._context(state if state is not None else reasoner._constants_state())
        self.adds: set[Atom] = set()
        self.deletes: set[Atom] = set()
        self.fluents: set[FluentKey] = set()

    def walk_and_effect(self, eff: AndEffect, b: Bindings) -> None:
        for sub in eff.effects:
            self.walk(sub, b)

    def walk_add_effect(self, eff: AddEffect, b: Bindings) -> None:
        self.adds.add(Atom(eff.atom.predicate, ground_args(eff.atom.args, b)))

    def walk_delete_effect(self, eff: DeleteEffect, b: Bindings) -> None:
        self.deletes.add(Atom(eff.atom.predicate, ground_args(eff.atom.args, b)))

    def walk_numeric_effect(self, eff: NumericEffect, b: Bindings) -> None:
        self.fluents.add((eff.fluent.name, ground_args(eff.fluent.args, b)))

    def walk_when_effect(self, eff: WhenEffect, b: Bindings) -> None:
        if not self.check or self.r._holds(eff.condition, b, self.ctx):
            self.walk(eff.effect, b)

    def walk_forall_effect(self, eff: ForallEffect, b: Bindings) -> None:
        for nb in self.r._enumerate(eff.variables, b, self.ctx):
            self.walk(eff.effect, nb)


def effect_atoms(
    reasoner: Reasoner, effect: Effect, bindings: dict[str, str], state: State | None
) -> tuple[set[Atom], set[Atom], set[FluentKey]]:
    """(adds, deletes, numeric fluent keys); see :meth:`Evaluator.effect_atoms`."""
    walker = _EffectAtoms(reasoner, state)
    walker.walk(effect, bindings)
    return walker.adds, walker.deletes, walker.fluents


class AtomWalker(Visitor[None]):
    """Collects the ground atoms and fluents a condition depends on
    (``walk(cond, bindings, positive)``)."""

    kinds = ("condition", "expression")

    def __init__(self, reasoner: Reasoner, state: State | None) -> None:
        self.r = reasoner
        self.state = state
        self.ctx = reasoner._context(state if state is not None else reasoner._constants_state())
        self.positive: set[Atom] = set()
        self.negative: set[Atom] = set()
        self.fluents: set[FluentKey] = set()
        self._expanding: set[tuple[str, Args]] = set()

    def _holds(self, cond: Condition, b: Bindings) -> bool:
        try:
            return self.r._holds(cond, b, self.ctx)
        except KnowledgeError:
            return False

    def _choose(self, options: list[tuple[Condition, Bindings]], positive: bool) -> None:
        """A disjunction: with a state, walk the first alternative that does its job."""
        if self.state is not None:
            for cond, b in options:
                if self._holds(cond, b) == positive:
                    self.walk(cond, b, positive)
                    return
        for cond, b in options:
            self.walk(cond, b, positive)

    def walk_atom(self, cond: Atom, b: Bindings, positive: bool) -> None:
        args = ground_args(cond.args, b)
        rules = self.r._derived_rules.get(cond.predicate)
        if rules is None:
            (self.positive if positive else self.negative).add(Atom(cond.predicate, args))
            return
        key = (cond.predicate, args)
        if key in self._expanding:
            return
        self._expanding.add(key)
        options: list[tuple[Condition, Bindings]] = []
        for rule in rules:
            rb = {p.name: a for p, a in zip(rule.head.parameters, args, strict=True)}
            options.append((rule.condition, rb))
        # Several rules for one head act like a disjunction of their bodies.
        if len(options) == 1:
            self.walk(options[0][0], options[0][1], positive)
        elif positive:
            self._choose(options, True)
        else:
            for c, option_b in options:
                self.walk(c, option_b, False)
        self._expanding.discard(key)

    def walk_and(self, cond: And, b: Bindings, positive: bool) -> None:
        if positive:
            for c in cond.operands:
                self.walk(c, b, True)
        else:
            self._choose([(c, b) for c in cond.operands], False)

    def walk_or(self, cond: Or, b: Bindings, positive: bool) -> None:
        if positive:
            self._choose([(c, b) for c in cond.operands], True)
        else:
            for c in cond.operands:
                self.walk(c, b, False)

    def walk_not(self, cond: Not, b: Bindings, positive: bool) -> None:
        self.walk(cond.operand, b, not positive)

    def walk_exists(self, cond: Exists | Forall, b: Bindings, positive: bool) -> None:
        groundings: list[tuple[Condition, Bindings]] = [
            (cond.body, nb) for nb in self.r._enumerate(cond.variables, b, self.ctx)
        ]
        if (type(cond) is Exists) == positive:  # some grounding is enough
            self._choose(groundings, positive)
        else:
            for body, nb in groundings:
                self.walk(body, nb, positive)

    walk_forall = walk_exists

    def walk_equals(self, cond: Equals, b: Bindings, positive: bool) -> None:
        return None

    def walk_compare(self, cond: Compare | Any, b: Bindings, positive: bool) -> None:
        for child in children(cond):
            self.walk(child, b, positive)

    walk_binary_op = walk_negate = walk_compare

    def walk_fluent_ref(self, expr: FluentRef, b: Bindings, positive: bool) -> None:
        self.fluents.add((expr.name, ground_args(expr.args, b)))

    def walk_number(self, expr: Any, b: Bindings, positive: bool) -> None:
        return None

    walk_duration_ref = walk_number
