"""Pure helpers on conditions and numeric expressions used by the evaluator.

Why separate: they know nothing about states or domains (flattening, pushing a
negation in, free variables, comparisons with a tolerance, the semi-naive rewrite),
so they are easy to test and to reuse without an evaluator.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

from plansys_bridge.knowledge.state import FluentKey
from plansys_bridge.pddl.model import (
    And,
    Atom,
    Compare,
    Condition,
    Equals,
    Exists,
    Forall,
    Imply,
    Not,
    Number,
    NumExpr,
    Or,
)
from plansys_bridge.pddl.walkers import Visitor, Walker, bound_variables, children, terms
from plansys_bridge.pddl.writer import PddlWriter

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


class _Describe(PddlWriter):
    """A numeric expression as text for error messages (numbers as ``repr``)."""

    kinds = ("expression",)

    def walk_number(self, expr: Number) -> str:
        return repr(expr.value)


_DESCRIBE = _Describe()


def describe_expr(expr: NumExpr) -> str:
    return _DESCRIBE.walk(expr)


def conjuncts(cond: Condition) -> list[Condition]:
    """Flatten nested ``and``s so a join sees every conjunct at once."""
    if type(cond) is And:
        out: list[Condition] = []
        for c in cond.operands:
            out.extend(conjuncts(c))
        return out
    return [cond]


class _Negate(Walker[Condition]):
    """``(not cond)`` with the negation pushed one level in where that gives atoms."""

    kinds = ("condition",)

    def walk_not(self, cond: Not) -> Condition:
        return cond.operand

    def walk_imply(self, cond: Imply) -> Condition:
        return And((cond.antecedent, self.walk(cond.consequent)))

    def walk_or(self, cond: Or) -> Condition:
        return And(tuple(self.walk(c) for c in cond.operands))

    def default(self, node: Any, *args: Any) -> Condition:
        return Not(node)


_NEGATE = _Negate()


def negate(cond: Condition) -> Condition:
    """``(not cond)`` with the negation pushed one level in, so a join can use atoms
    (``not (imply a b)`` becomes ``(and a (not b))``)."""
    return _NEGATE.walk(cond)


def free_vars(node: Condition | NumExpr) -> set[str]:
    """Variables a condition or expression reads that no quantifier inside it binds."""
    out = {t for t in terms(node) if t[:1] == "?"}
    for child in children(node):
        out |= free_vars(child)
    bound = bound_variables(node)
    return out.difference(bound) if bound else out


def expr_vars(expr: NumExpr) -> set[str]:
    return free_vars(expr)


class _DeltaVariants(Visitor[list[Condition]]):
    """Copies of a condition with one positive use of a ``names`` predicate renamed to
    its delta table (semi-naive evaluation)."""

    kinds = ("condition",)

    def walk_atom(self, cond: Atom, names: set[str]) -> list[Condition]:
        return [Atom(cond.predicate + DELTA, cond.args)] if cond.predicate in names else []

    def walk_and(self, cond: And, names: set[str]) -> list[Condition]:
        return [And(ops) for ops in self._operands(cond.operands, names)]

    def walk_or(self, cond: Or, names: set[str]) -> list[Condition]:
        return [Or(ops) for ops in self._operands(cond.operands, names)]

    def _operands(
        self, ops: tuple[Condition, ...], names: set[str]
    ) -> Iterator[tuple[Condition, ...]]:
        for i, op in enumerate(ops):
            for v in self.walk(op, names):
                yield (*ops[:i], v, *ops[i + 1 :])

    def walk_exists(self, cond: Exists, names: set[str]) -> list[Condition]:
        return [Exists(cond.variables, v) for v in self.walk(cond.body, names)]

    def walk_imply(self, cond: Imply, names: set[str]) -> list[Condition]:
        return [Imply(cond.antecedent, v) for v in self.walk(cond.consequent, names)]

    def _none(self, cond: Condition, names: set[str]) -> list[Condition]:
        return []  # negative uses (and comparisons) are read from complete tables

    walk_not = walk_forall = walk_equals = walk_compare = _none


_DELTA_VARIANTS = _DeltaVariants()


def delta_variants(cond: Condition, names: set[str]) -> list[Condition]:
    """Copies of ``cond`` with one positive use of a ``names`` predicate renamed to its
    delta table (semi-naive evaluation)."""
    return _DELTA_VARIANTS.walk(cond, names)


class _PredicateUses(Visitor[None]):
    """(predicate, needs-complete-knowledge) for every atom of a condition."""

    kinds = ("condition",)

    def __init__(self) -> None:
        self.found: list[tuple[str, bool]] = []

    def walk_atom(self, cond: Atom, negative: bool) -> None:
        self.found.append((cond.predicate, negative))

    def walk_and(self, cond: And | Or, negative: bool) -> None:
        for c in cond.operands:
            self.walk(c, negative)

    walk_or = walk_and

    def walk_not(self, cond: Not, negative: bool) -> None:
        self.walk(cond.operand, True)

    def walk_imply(self, cond: Imply, negative: bool) -> None:
        self.walk(cond.antecedent, True)
        self.walk(cond.consequent, negative)

    def walk_exists(self, cond: Exists, negative: bool) -> None:
        self.walk(cond.body, negative)

    def walk_forall(self, cond: Forall, negative: bool) -> None:
        self.walk(cond.body, True)

    def walk_equals(self, cond: Equals | Compare, negative: bool) -> None:
        return None

    walk_compare = walk_equals


def predicate_uses(cond: Condition, negative: bool) -> Iterator[tuple[str, bool]]:
    """(predicate, needs-complete-knowledge) for every atom of a condition."""
    walker = _PredicateUses()
    walker.walk(cond, negative)
    return iter(walker.found)
