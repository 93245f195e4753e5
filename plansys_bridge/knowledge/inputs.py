"""What the knowledge base accepts from Python callers, checked before it is stored.

The text form (PDDL) is checked by the parser; model objects handed in directly skip
the parser, so their shape is checked here: a number must be a real, finite value a
float can hold (NaN compares false with everything, infinity and ``10**400`` cannot be
written back as PDDL), a name must be text, a goal must be a condition. Whatever the
knowledge base holds can then always be written, published and evaluated.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.pddl.model import (
    And,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DurationRef,
    FluentRef,
    FluentValue,
    Number,
    Or,
    TypedName,
)
from plansys_bridge.pddl.walkers import NODE_KINDS, Walker, children, terms

__all__ = ["check_atom", "check_condition", "check_fluent_value", "check_text", "number"]

_BINARY_OPS = ("+", "-", "*", "/")
_COMPARE_OPS = ("<", "<=", "=", ">=", ">")


def number(value: object, what: str) -> float:
    """``value`` as a float, or KnowledgeError when it is not a real, finite number."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise KnowledgeError(f"{what}: {_short(value)} is not a number")
    try:
        result = float(value)
    except OverflowError:
        raise KnowledgeError(f"{what}: {_short(value)} is beyond the range of a float") from None
    if not math.isfinite(result):
        raise KnowledgeError(f"{what}: {value!r} is not a finite number")
    return result


def check_text(value: object, what: str) -> str:
    """``value`` when it is a string; KnowledgeError naming its type otherwise."""
    if not isinstance(value, str):
        raise KnowledgeError(f"{what} must be text, got {type(value).__name__} {_short(value)}")
    return value


def check_atom(atom: Atom, what: str) -> Atom:
    """An Atom whose predicate and arguments are strings."""
    check_text(atom.predicate, f"{what} predicate name")
    if not isinstance(atom.args, tuple):
        raise KnowledgeError(f"{what} arguments must be a tuple of names")
    for arg in atom.args:
        check_text(arg, f"{what} argument")
    return atom


def check_fluent_value(fv: FluentValue, what: str = "function") -> FluentValue:
    """A FluentValue with a named fluent and a real number, the value made a float."""
    _check_fluent_ref(fv.fluent, what)
    value = number(fv.value, f"{what} ({' '.join((fv.fluent.name, *fv.fluent.args))})")
    return fv if type(fv.value) is float else FluentValue(fv.fluent, value)


def check_condition(cond: object, what: str = "goal") -> Condition:
    """A condition tree built only of condition and expression nodes with valid leaves."""
    _SHAPE.walk(cond, what, "condition")
    return cond  # type: ignore[return-value]  # checked node by node


_WRONG_KIND = {
    "condition": "is not a condition",
    "expression": "is not a numeric expression (numbers are Number(value))",
}


class _Shape(Walker[None]):
    """Checks a node handed in from Python is a model node of the kind its place
    needs (``walk(node, what, kind)``), then its leaves and children. A construct
    without a method here (one with a ``lower()``) has its terms, variables and
    children checked generically."""

    kinds = ("condition", "expression")

    def walk(self, node: Any, *args: Any) -> None:
        what, kind = args
        if type(node) not in NODE_KINDS[kind] and not (
            kind == "condition" and dataclasses.is_dataclass(node) and hasattr(node, "lower")
        ):
            raise KnowledgeError(
                f"{what}: {type(node).__name__} {_short(node)} {_WRONG_KIND[kind]}"
            )
        super().walk(node, what, kind)

    def default(self, node: Any, what: str, kind: str) -> None:
        for term in terms(node):
            check_text(term, f"{what} term")
        for var in getattr(node, "variables", ()):
            if not isinstance(var, TypedName):
                raise KnowledgeError(f"{what}: quantified variables must be TypedNames")
            check_text(var.name, f"{what} variable")
        for child in children(node):
            child_kind = "expression" if type(child) in NODE_KINDS["expression"] else kind
            self.walk(child, what, child_kind)

    def walk_atom(self, node: Atom, what: str, kind: str) -> None:
        check_atom(node, what)

    def walk_and(self, node: And | Or, what: str, kind: str) -> None:
        if not isinstance(node.operands, tuple):
            raise KnowledgeError(f"{what}: operands must be a tuple of conditions")
        for operand in node.operands:
            self.walk(operand, what, "condition")

    walk_or = walk_and

    def walk_compare(self, node: Compare, what: str, kind: str) -> None:
        if node.op not in _COMPARE_OPS:
            raise KnowledgeError(f"{what}: unknown comparison {_short(node.op)}")
        self.walk(node.left, what, "expression")
        self.walk(node.right, what, "expression")

    def walk_number(self, node: Number, what: str, kind: str) -> None:
        number(node.value, what)

    def walk_fluent_ref(self, node: FluentRef, what: str, kind: str) -> None:
        _check_fluent_ref(node, what)

    def walk_binary_op(self, node: BinaryOp, what: str, kind: str) -> None:
        if node.op not in _BINARY_OPS:
            raise KnowledgeError(f"{what}: unknown operator {_short(node.op)}")
        self.walk(node.left, what, "expression")
        self.walk(node.right, what, "expression")

    def walk_duration_ref(self, node: DurationRef, what: str, kind: str) -> None:
        raise KnowledgeError(f"{what}: ?duration is only meaningful inside an action")


_SHAPE = _Shape()


def _check_fluent_ref(ref: object, what: str) -> None:
    if not isinstance(ref, FluentRef):
        raise KnowledgeError(f"{what}: {_short(ref)} is not a FluentRef")
    check_text(ref.name, f"{what} name")
    if not isinstance(ref.args, tuple):
        raise KnowledgeError(f"{what} arguments must be a tuple of names")
    for arg in ref.args:
        check_text(arg, f"{what} argument")


def _short(value: object, limit: int = 40) -> str:
    """A repr cut to ``limit`` characters (``10**400`` has 401 digits)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**limit:
        return f"an integer of {len(str(abs(value)))} digits"
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."
