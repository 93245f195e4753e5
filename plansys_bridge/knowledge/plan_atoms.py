"""Which ground atoms and fluents a condition needs and an effect changes.

The executor's plan graph links a step that needs an atom to the step that makes it
true (and orders steps whose effects would break another's requirement), so it asks
these questions for every step; the evaluator's ``condition_atoms``,
``condition_fluents`` and ``effect_atoms`` methods delegate here.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.grounding import ground_args
from plansys_bridge.knowledge.state import Args, FluentKey, State
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DeleteEffect,
    Effect,
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
    WhenEffect,
)

if TYPE_CHECKING:
    from plansys_bridge.knowledge.evaluation import Evaluator


def effect_atoms(
    ev: Evaluator, effect: Effect, bindings: dict[str, str], state: State | None
) -> tuple[set[Atom], set[Atom], set[FluentKey]]:
    """(adds, deletes, numeric fluent keys); see :meth:`Evaluator.effect_atoms`."""
    adds: set[Atom] = set()
    deletes: set[Atom] = set()
    fluents: set[FluentKey] = set()
    ctx = ev._context(state if state is not None else ev._constants_state())
    check = state is not None

    def visit(eff: Effect, b: dict[str, str]) -> None:
        if isinstance(eff, AndEffect):
            for sub in eff.effects:
                visit(sub, b)
        elif isinstance(eff, AddEffect):
            adds.add(Atom(eff.atom.predicate, ground_args(eff.atom.args, b)))
        elif isinstance(eff, DeleteEffect):
            deletes.add(Atom(eff.atom.predicate, ground_args(eff.atom.args, b)))
        elif isinstance(eff, NumericEffect):
            fluents.add((eff.fluent.name, ground_args(eff.fluent.args, b)))
        elif isinstance(eff, WhenEffect):
            if not check or ev._holds(eff.condition, b, ctx):
                visit(eff.effect, b)
        elif isinstance(eff, ForallEffect):
            for nb in ev._enumerate(eff.variables, b, ctx):
                visit(eff.effect, nb)

    visit(effect, bindings)
    return adds, deletes, fluents


class AtomWalker:
    """Collects the ground atoms and fluents a condition depends on."""

    def __init__(self, ev: Evaluator, state: State | None) -> None:
        self.ev = ev
        self.state = state
        self.ctx = ev._context(state if state is not None else ev._constants_state())
        self.positive: set[Atom] = set()
        self.negative: set[Atom] = set()
        self.fluents: set[FluentKey] = set()
        self._expanding: set[tuple[str, Args]] = set()

    def _holds(self, cond: Condition, b: Mapping[str, str]) -> bool:
        try:
            return self.ev._holds(cond, b, self.ctx)
        except KnowledgeError:
            return False

    def _choose(self, options: list[tuple[Condition, dict[str, str]]], positive: bool) -> None:
        """A disjunction: with a state, walk the first alternative that does its job."""
        if self.state is not None:
            for cond, b in options:
                if self._holds(cond, b) == positive:
                    self.walk(cond, b, positive)
                    return
        for cond, b in options:
            self.walk(cond, b, positive)

    def walk(self, cond: Condition, b: dict[str, str], positive: bool) -> None:
        if isinstance(cond, Atom):
            args = ground_args(cond.args, b)
            rules = self.ev._derived_rules.get(cond.predicate)
            if rules is None:
                (self.positive if positive else self.negative).add(Atom(cond.predicate, args))
                return
            key = (cond.predicate, args)
            if key in self._expanding:
                return
            self._expanding.add(key)
            options = []
            for rule in rules:
                rb = {p.name: a for p, a in zip(rule.head.parameters, args, strict=True)}
                options.append((rule.condition, rb))
            # Several rules for one head act like a disjunction of their bodies.
            if len(options) == 1:
                self.walk(options[0][0], options[0][1], positive)
            elif positive:
                self._choose(options, True)
            else:
                for c, rb in options:
                    self.walk(c, rb, False)
            self._expanding.discard(key)
        elif isinstance(cond, And):
            if positive:
                for c in cond.operands:
                    self.walk(c, b, True)
            else:
                self._choose([(c, b) for c in cond.operands], False)
        elif isinstance(cond, Or):
            if positive:
                self._choose([(c, b) for c in cond.operands], True)
            else:
                for c in cond.operands:
                    self.walk(c, b, False)
        elif isinstance(cond, Not):
            self.walk(cond.operand, b, not positive)
        elif isinstance(cond, Imply):
            self.walk(Or((Not(cond.antecedent), cond.consequent)), b, positive)
        elif isinstance(cond, (Exists, Forall)):
            groundings = [(cond.body, nb) for nb in self.ev._enumerate(cond.variables, b, self.ctx)]
            disjunctive = isinstance(cond, Exists) == positive
            if disjunctive:
                self._choose(groundings, positive)
            else:
                for body, nb in groundings:
                    self.walk(body, nb, positive)
        elif isinstance(cond, Compare):
            self._expr(cond.left, b)
            self._expr(cond.right, b)

    def _expr(self, expr: NumExpr, b: Mapping[str, str]) -> None:
        if isinstance(expr, FluentRef):
            self.fluents.add((expr.name, ground_args(expr.args, b)))
        elif isinstance(expr, BinaryOp):
            self._expr(expr.left, b)
            self._expr(expr.right, b)
        elif isinstance(expr, Negate):
            self._expr(expr.operand, b)
