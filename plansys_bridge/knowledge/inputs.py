"""What the knowledge base accepts from Python callers, checked before it is stored.

The text form (PDDL) is checked by the parser; model objects handed in directly skip
the parser, so their shape is checked here: a number must be a real, finite value a
float can hold (NaN compares false with everything, infinity and ``10**400`` cannot be
written back as PDDL), a name must be text, a goal must be a condition. Whatever the
knowledge base holds can then always be written, published and evaluated.
"""

from __future__ import annotations

import math

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.pddl.model import (
    And,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DurationRef,
    Equals,
    Exists,
    FluentRef,
    FluentValue,
    Forall,
    Imply,
    Negate,
    Not,
    Number,
    NumExpr,
    Or,
    TypedName,
)

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
    stack: list[object] = [cond]
    while stack:
        node = stack.pop()
        if isinstance(node, Atom):
            check_atom(node, what)
        elif isinstance(node, And | Or):
            if not isinstance(node.operands, tuple):
                raise KnowledgeError(f"{what}: operands must be a tuple of conditions")
            stack.extend(node.operands)
        elif isinstance(node, Not):
            stack.append(node.operand)
        elif isinstance(node, Imply):
            stack += [node.antecedent, node.consequent]
        elif isinstance(node, Exists | Forall):
            for var in node.variables:
                if not isinstance(var, TypedName):
                    raise KnowledgeError(f"{what}: quantified variables must be TypedNames")
                check_text(var.name, f"{what} variable")
            stack.append(node.body)
        elif isinstance(node, Equals):
            check_text(node.left, f"{what} term")
            check_text(node.right, f"{what} term")
        elif isinstance(node, Compare):
            if node.op not in _COMPARE_OPS:
                raise KnowledgeError(f"{what}: unknown comparison {_short(node.op)}")
            _check_expr(node.left, what)
            _check_expr(node.right, what)
        else:
            raise KnowledgeError(f"{what}: {type(node).__name__} {_short(node)} is not a condition")
    return cond  # type: ignore[return-value]  # checked node by node above


def _check_expr(expr: NumExpr, what: str) -> None:
    stack: list[object] = [expr]
    while stack:
        node = stack.pop()
        if isinstance(node, Number):
            number(node.value, what)
        elif isinstance(node, FluentRef):
            _check_fluent_ref(node, what)
        elif isinstance(node, BinaryOp):
            if node.op not in _BINARY_OPS:
                raise KnowledgeError(f"{what}: unknown operator {_short(node.op)}")
            stack += [node.left, node.right]
        elif isinstance(node, Negate):
            stack.append(node.operand)
        elif isinstance(node, DurationRef):
            raise KnowledgeError(f"{what}: ?duration is only meaningful inside an action")
        else:
            raise KnowledgeError(
                f"{what}: {type(node).__name__} {_short(node)} is not a numeric expression "
                "(numbers are Number(value))"
            )


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
