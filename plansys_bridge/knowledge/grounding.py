"""Substituting objects for variables, and the ground action the executor runs.

Why substitution produces new model nodes instead of carrying bindings around: a
ground action's conditions are then self-contained (they print as PDDL, compare and
hash), so the plan graph, the validator and the monitor can share them freely.
Quantified variables are left alone (an inner ``?x`` shadows an outer one).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    AnyAction,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DeleteEffect,
    DurationRef,
    Effect,
    Equals,
    Exists,
    FluentRef,
    Forall,
    ForallEffect,
    Imply,
    Negate,
    Not,
    Number,
    NumericEffect,
    NumExpr,
    Or,
    TypedName,
    WhenEffect,
)


class UnboundVariableError(KnowledgeError):
    """A condition or effect used a variable no parameter or quantifier binds."""


def normalize_bindings(bindings: Mapping[str, str]) -> dict[str, str]:
    """Accept ``{"?r": "r2d2"}`` or ``{"r": "r2d2"}``; keys and values lower-case."""
    out: dict[str, str] = {}
    for key, value in bindings.items():
        name = key.lower()
        out[name if name.startswith("?") else "?" + name] = value.lower()
    return out


def ground_term(term: str, bindings: Mapping[str, str]) -> str:
    if term.startswith("?"):
        try:
            return bindings[term]
        except KeyError:
            raise UnboundVariableError(f"variable {term} is not bound") from None
    return term


def ground_args(args: tuple[str, ...], bindings: Mapping[str, str]) -> tuple[str, ...]:
    """Replace variables by their objects; an unbound variable is an error naming it."""
    try:
        return tuple(bindings[a] if a[:1] == "?" else a for a in args)
    except KeyError as exc:
        raise UnboundVariableError(f"variable {exc.args[0]} is not bound") from None


def _shadow(bindings: Mapping[str, str], variables: tuple[TypedName, ...]) -> Mapping[str, str]:
    names = {v.name for v in variables}
    if not names.intersection(bindings):
        return bindings
    return {k: v for k, v in bindings.items() if k not in names}


def _sub_args(args: tuple[str, ...], b: Mapping[str, str]) -> tuple[str, ...]:
    return tuple(b.get(a, a) if a[:1] == "?" else a for a in args)


def substitute_expr(expr: NumExpr, b: Mapping[str, str]) -> NumExpr:
    if isinstance(expr, FluentRef):
        return FluentRef(expr.name, _sub_args(expr.args, b), expr.loc)
    if isinstance(expr, BinaryOp):
        return BinaryOp(expr.op, substitute_expr(expr.left, b), substitute_expr(expr.right, b))
    if isinstance(expr, Negate):
        return Negate(substitute_expr(expr.operand, b))
    return expr  # Number, DurationRef


def substitute_condition(cond: Condition, b: Mapping[str, str]) -> Condition:
    """``cond`` with bound variables replaced; unbound ones are kept as variables."""
    if not b:
        return cond
    if isinstance(cond, Atom):
        return Atom(cond.predicate, _sub_args(cond.args, b), cond.loc)
    if isinstance(cond, And):
        return And(tuple(substitute_condition(c, b) for c in cond.operands))
    if isinstance(cond, Not):
        return Not(substitute_condition(cond.operand, b))
    if isinstance(cond, Or):
        return Or(tuple(substitute_condition(c, b) for c in cond.operands))
    if isinstance(cond, Imply):
        return Imply(
            substitute_condition(cond.antecedent, b), substitute_condition(cond.consequent, b)
        )
    if isinstance(cond, Exists):
        return Exists(cond.variables, substitute_condition(cond.body, _shadow(b, cond.variables)))
    if isinstance(cond, Forall):
        return Forall(cond.variables, substitute_condition(cond.body, _shadow(b, cond.variables)))
    if isinstance(cond, Equals):
        return Equals(b.get(cond.left, cond.left), b.get(cond.right, cond.right))
    if isinstance(cond, Compare):
        return Compare(cond.op, substitute_expr(cond.left, b), substitute_expr(cond.right, b))
    raise TypeError(f"not a condition: {cond!r}")


def substitute_effect(effect: Effect, b: Mapping[str, str]) -> Effect:
    """``effect`` with bound variables replaced."""
    if not b:
        return effect
    if isinstance(effect, AddEffect):
        return AddEffect(substitute_condition(effect.atom, b))  # type: ignore[arg-type]
    if isinstance(effect, DeleteEffect):
        return DeleteEffect(substitute_condition(effect.atom, b))  # type: ignore[arg-type]
    if isinstance(effect, NumericEffect):
        fluent = FluentRef(effect.fluent.name, _sub_args(effect.fluent.args, b), effect.fluent.loc)
        return NumericEffect(effect.op, fluent, substitute_expr(effect.value, b))
    if isinstance(effect, AndEffect):
        return AndEffect(tuple(substitute_effect(e, b) for e in effect.effects))
    if isinstance(effect, WhenEffect):
        return WhenEffect(
            substitute_condition(effect.condition, b), substitute_effect(effect.effect, b)
        )
    if isinstance(effect, ForallEffect):
        return ForallEffect(
            effect.variables, substitute_effect(effect.effect, _shadow(b, effect.variables))
        )
    raise TypeError(f"not an effect: {effect!r}")


@dataclass(frozen=True, eq=False)
class GroundAction:
    """An action with its parameters replaced by objects.

    A plain ``:action`` is seen the way PlanSys2's executor sees it: its precondition
    must hold over all of its execution and its effect happens at the end.
    """

    name: str
    args: tuple[str, ...]
    bindings: Mapping[str, str]
    at_start: Condition
    over_all: Condition
    at_end: Condition
    start_effect: Effect
    end_effect: Effect
    duration: float | None
    durative: bool = False
    action: AnyAction | None = field(default=None, repr=False)

    @property
    def full_name(self) -> str:
        """``(move r2d2 kitchen bedroom)``."""
        return "(" + " ".join((self.name, *self.args)) + ")"

    def __str__(self) -> str:
        return self.full_name

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, GroundAction):
            return NotImplemented
        return (
            self.name == other.name and self.args == other.args and self.duration == other.duration
        )

    def __hash__(self) -> int:
        return hash((self.name, self.args))


__all__ = [
    "DurationRef",
    "GroundAction",
    "Number",
    "UnboundVariableError",
    "ground_args",
    "ground_term",
    "normalize_bindings",
    "substitute_condition",
    "substitute_effect",
    "substitute_expr",
]
