"""What an effect reads and how it writes: the accesses the plan graph orders.

A conditional effect reads its condition, a numeric effect reads the fluents of its
value, and numeric updates of one kind (increases, scalings) commute with each
other while an assignment commutes with nothing. The plan graph builder uses these
to decide which happenings must keep their plan order.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    TRUE,
    AndEffect,
    BinaryOp,
    Effect,
    FluentRef,
    ForallEffect,
    Negate,
    NumExpr,
    WhenEffect,
    is_variable,
)

__all__ = ["expr_fluents", "ground_fluent", "numeric_class", "walk_effect"]


def numeric_class(op: str) -> str:
    if op in ("increase", "decrease"):
        return "add"
    if op in ("scale-up", "scale-down"):
        return "mul"
    return "assign"


def walk_effect(
    effect: Effect, bindings: Mapping[str, str], ev: Evaluator, state: State
) -> Iterator[tuple[Effect, Mapping[str, str]]]:
    """Sub-effects with their bindings; a ``forall`` is expanded over the objects of
    its variables' types in ``state`` (as the evaluator applies it)."""
    if isinstance(effect, AndEffect):
        for sub in effect.effects:
            yield from walk_effect(sub, bindings, ev, state)
    elif isinstance(effect, WhenEffect):
        yield effect, bindings
        yield from walk_effect(effect.effect, bindings, ev, state)
    elif isinstance(effect, ForallEffect):
        for found in ev.satisfying_bindings(TRUE, state, effect.variables, bindings):
            yield from walk_effect(effect.effect, {**bindings, **found}, ev, state)
    else:
        yield effect, bindings


def ground_fluent(ref: FluentRef, bindings: Mapping[str, str]) -> FluentKey | None:
    args = tuple(bindings.get(a, a) if is_variable(a) else a for a in ref.args)
    if any(is_variable(a) for a in args):
        return None
    return (ref.name, args)


def expr_fluents(expr: NumExpr, bindings: Mapping[str, str]) -> set[FluentKey]:
    if isinstance(expr, FluentRef):
        key = ground_fluent(expr, bindings)
        return {key} if key is not None else set()
    if isinstance(expr, BinaryOp):
        return expr_fluents(expr.left, bindings) | expr_fluents(expr.right, bindings)
    if isinstance(expr, Negate):
        return expr_fluents(expr.operand, bindings)
    return set()
