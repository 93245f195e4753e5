"""Pure helpers on conditions and numeric expressions used by the evaluator.

Why separate: they know nothing about states or domains (flattening, pushing a
negation in, free variables, comparisons with a tolerance, the semi-naive rewrite),
so they are easy to test and to reuse without an evaluator.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

from plansys_bridge.knowledge.state import FluentKey
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
    Forall,
    Imply,
    Negate,
    Not,
    Number,
    NumExpr,
    Or,
)

DELTA = "#delta"
"""Suffix of the predicate name a semi-naive variant reads its new facts from."""


def compare(op: str, left: float, right: float) -> bool:
    if op == "=":
        return math.isclose(left, right, rel_tol=1e-9, abs_tol=1e-9)
    if op == "<":
        return left < right
    if op == "<=":
        return left <= right or math.isclose(left, right, rel_tol=1e-9, abs_tol=1e-9)
    if op == ">":
        return left > right
    if op == ">=":
        return left >= right or math.isclose(left, right, rel_tol=1e-9, abs_tol=1e-9)
    raise ValueError(f"unknown comparison {op}")


def fluent_text(key: FluentKey) -> str:
    return "(" + " ".join((key[0], *key[1])) + ")"


def describe_expr(expr: NumExpr) -> str:
    if isinstance(expr, Number):
        return repr(expr.value)
    if isinstance(expr, FluentRef):
        return "(" + " ".join((expr.name, *expr.args)) + ")"
    if isinstance(expr, DurationRef):
        return "?duration"
    if isinstance(expr, Negate):
        return f"(- {describe_expr(expr.operand)})"
    return f"({expr.op} {describe_expr(expr.left)} {describe_expr(expr.right)})"


def conjuncts(cond: Condition) -> list[Condition]:
    """Flatten nested ``and``s so a join sees every conjunct at once."""
    if isinstance(cond, And):
        out: list[Condition] = []
        for c in cond.operands:
            out.extend(conjuncts(c))
        return out
    return [cond]


def negate(cond: Condition) -> Condition:
    """``(not cond)`` with the negation pushed one level in, so a join can use atoms
    (``not (imply a b)`` becomes ``(and a (not b))``)."""
    if isinstance(cond, Not):
        return cond.operand
    if isinstance(cond, Imply):
        return And((cond.antecedent, negate(cond.consequent)))
    if isinstance(cond, Or):
        return And(tuple(negate(c) for c in cond.operands))
    return Not(cond)


def free_vars(cond: Condition) -> set[str]:
    if isinstance(cond, Atom):
        return {a for a in cond.args if a[:1] == "?"}
    if isinstance(cond, (And, Or)):
        out: set[str] = set()
        for c in cond.operands:
            out |= free_vars(c)
        return out
    if isinstance(cond, Not):
        return free_vars(cond.operand)
    if isinstance(cond, Imply):
        return free_vars(cond.antecedent) | free_vars(cond.consequent)
    if isinstance(cond, (Exists, Forall)):
        return free_vars(cond.body) - {v.name for v in cond.variables}
    if isinstance(cond, Equals):
        return {a for a in (cond.left, cond.right) if a[:1] == "?"}
    if isinstance(cond, Compare):
        return expr_vars(cond.left) | expr_vars(cond.right)
    return set()


def expr_vars(expr: NumExpr) -> set[str]:
    if isinstance(expr, FluentRef):
        return {a for a in expr.args if a[:1] == "?"}
    if isinstance(expr, BinaryOp):
        return expr_vars(expr.left) | expr_vars(expr.right)
    if isinstance(expr, Negate):
        return expr_vars(expr.operand)
    return set()


def delta_variants(cond: Condition, names: set[str]) -> list[Condition]:
    """Copies of ``cond`` with one positive use of a ``names`` predicate renamed to its
    delta table (semi-naive evaluation)."""
    if isinstance(cond, Atom):
        return [Atom(cond.predicate + DELTA, cond.args)] if cond.predicate in names else []
    if isinstance(cond, (And, Or)):
        out: list[Condition] = []
        ops = cond.operands
        for i, op in enumerate(ops):
            for v in delta_variants(op, names):
                replaced = (*ops[:i], v, *ops[i + 1 :])
                out.append(And(replaced) if isinstance(cond, And) else Or(replaced))
        return out
    if isinstance(cond, Exists):
        return [Exists(cond.variables, v) for v in delta_variants(cond.body, names)]
    if isinstance(cond, Imply):
        return [Imply(cond.antecedent, v) for v in delta_variants(cond.consequent, names)]
    return []


def predicate_uses(cond: Condition, negative: bool) -> Iterator[tuple[str, bool]]:
    """(predicate, needs-complete-knowledge) for every atom of a condition."""
    if isinstance(cond, Atom):
        yield cond.predicate, negative
    elif isinstance(cond, (And, Or)):
        for c in cond.operands:
            yield from predicate_uses(c, negative)
    elif isinstance(cond, Not):
        yield from predicate_uses(cond.operand, True)
    elif isinstance(cond, Imply):
        yield from predicate_uses(cond.antecedent, True)
        yield from predicate_uses(cond.consequent, negative)
    elif isinstance(cond, Exists):
        yield from predicate_uses(cond.body, negative)
    elif isinstance(cond, Forall):
        yield from predicate_uses(cond.body, True)
