"""What an effect reads and how it writes: the accesses the plan graph orders.

A conditional effect reads its condition, a numeric effect reads the fluents of its
value, and numeric updates of one kind (increases, scalings) commute with each
other while an assignment commutes with nothing. The plan graph builder uses these
to decide which happenings must keep their plan order. Effects and expressions
are walked with :mod:`plansys_bridge.pddl.walkers`, so a new construct is walked
here as its lowered form without an edit.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    TRUE,
    AndEffect,
    Effect,
    FluentRef,
    ForallEffect,
    NumExpr,
    WhenEffect,
    is_variable,
)
from plansys_bridge.pddl.walkers import Visitor, iter_nodes

__all__ = ["expr_fluents", "ground_fluent", "numeric_class", "walk_effect"]

Parts = Iterator[tuple[Effect, Mapping[str, str]]]


def numeric_class(op: str) -> str:
    """Which numeric updates commute: ``add`` (increase/decrease) with each other,
    ``mul`` (scalings) with each other, an ``assign`` with nothing."""
    if op in ("increase", "decrease"):
        return "add"
    if op in ("scale-up", "scale-down"):
        return "mul"
    return "assign"


def walk_effect(effect: Effect, bindings: Mapping[str, str], ev: Evaluator, state: State) -> Parts:
    """Sub-effects with their bindings: every conditional effect (its condition is
    read) and every leaf; a ``forall`` is expanded over the objects of its
    variables' types in ``state`` (as the evaluator applies it)."""
    return _EffectParts(ev, state).walk(effect, bindings)


class _EffectParts(Visitor[Parts]):
    kinds = ("effect",)

    def __init__(self, ev: Evaluator, state: State) -> None:
        self.ev = ev
        self.state = state

    def walk_and_effect(self, effect: AndEffect, bindings: Mapping[str, str]) -> Parts:
        for sub in effect.effects:
            yield from self.walk(sub, bindings)

    def walk_when_effect(self, effect: WhenEffect, bindings: Mapping[str, str]) -> Parts:
        yield effect, bindings
        yield from self.walk(effect.effect, bindings)

    def walk_forall_effect(self, effect: ForallEffect, bindings: Mapping[str, str]) -> Parts:
        for found in self.ev.satisfying_bindings(TRUE, self.state, effect.variables, bindings):
            yield from self.walk(effect.effect, {**bindings, **found})

    def _leaf(self, effect: Effect, bindings: Mapping[str, str]) -> Parts:
        yield effect, bindings

    walk_add_effect = walk_delete_effect = walk_numeric_effect = _leaf


def ground_fluent(ref: FluentRef, bindings: Mapping[str, str]) -> FluentKey | None:
    """``ref`` with ``bindings`` substituted, or None while a variable is left."""
    args = tuple(bindings.get(a, a) if is_variable(a) else a for a in ref.args)
    if any(is_variable(a) for a in args):
        return None
    return (ref.name, args)


def expr_fluents(expr: NumExpr, bindings: Mapping[str, str]) -> set[FluentKey]:
    """The ground fluents a numeric expression reads."""
    keys = (ground_fluent(n, bindings) for n in iter_nodes(expr) if isinstance(n, FluentRef))
    return {key for key in keys if key is not None}
