"""Model -> PDDL text, such that parsing the text gives back an equal model.

Used to hand domains/problems to external planners, to show the knowledge in the
terminal and to publish it. Output is plain and stable (one declaration per line,
two-space indent); it makes no attempt to reproduce the original layout.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from plansys_bridge.pddl.model import (
    TRUE,
    Action,
    AddEffect,
    And,
    AndEffect,
    Atom,
    BinaryOp,
    Compare,
    Condition,
    DeleteEffect,
    DerivedPredicate,
    Domain,
    DurationRef,
    DurativeAction,
    Effect,
    Equals,
    Exists,
    FluentRef,
    FluentValue,
    Forall,
    ForallEffect,
    FunctionDef,
    Imply,
    Metric,
    Negate,
    Not,
    Number,
    NumericEffect,
    NumExpr,
    Or,
    PredicateDef,
    Problem,
    TypedName,
    WhenEffect,
)
from plansys_bridge.pddl.walkers import Visitor

__all__ = [
    "PddlWriter",
    "write_atom",
    "write_condition",
    "write_domain",
    "write_effect",
    "write_fluent_value",
    "write_num_expr",
    "write_problem",
]


def write_number(value: float) -> str:
    """Integral values without a fraction, others with ``repr`` (exact round trip)."""
    if not math.isfinite(value):
        raise ValueError(f"PDDL has no notation for {value}")
    if value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


def _types(types: tuple[str, ...]) -> str:
    return types[0] if len(types) == 1 else "(either " + " ".join(types) + ")"


def _typed(names: Iterable[TypedName]) -> str:
    return " ".join(f"{n.name} - {_types(n.types)}" for n in names)


def _app(head: str, args: Iterable[str]) -> str:
    return "(" + " ".join((head, *args)) + ")"


def write_atom(atom: Atom) -> str:
    return _app(atom.predicate, atom.args)


class PddlWriter(Visitor[str]):
    """One PDDL form per node; a construct without one is written as its ``lower()``."""

    def walk_number(self, expr: Number) -> str:
        return write_number(expr.value)

    def walk_fluent_ref(self, expr: FluentRef) -> str:
        return _app(expr.name, expr.args)

    def walk_duration_ref(self, expr: DurationRef) -> str:
        return "?duration"

    def walk_binary_op(self, expr: BinaryOp) -> str:
        return f"({expr.op} {self.walk(expr.left)} {self.walk(expr.right)})"

    def walk_negate(self, expr: Negate) -> str:
        return f"(- {self.walk(expr.operand)})"

    def walk_atom(self, cond: Atom) -> str:
        return _app(cond.predicate, cond.args)

    def walk_and(self, cond: And) -> str:
        return _app("and", (self.walk(c) for c in cond.operands))

    def walk_or(self, cond: Or) -> str:
        return _app("or", (self.walk(c) for c in cond.operands))

    def walk_not(self, cond: Not) -> str:
        return f"(not {self.walk(cond.operand)})"

    def walk_imply(self, cond: Imply) -> str:
        return f"(imply {self.walk(cond.antecedent)} {self.walk(cond.consequent)})"

    def walk_exists(self, cond: Exists) -> str:
        return f"(exists ({_typed(cond.variables)}) {self.walk(cond.body)})"

    def walk_forall(self, cond: Forall) -> str:
        return f"(forall ({_typed(cond.variables)}) {self.walk(cond.body)})"

    def walk_compare(self, cond: Compare) -> str:
        return f"({cond.op} {self.walk(cond.left)} {self.walk(cond.right)})"

    def walk_equals(self, cond: Equals) -> str:
        return f"(= {cond.left} {cond.right})"

    def walk_add_effect(self, eff: AddEffect) -> str:
        return self.walk(eff.atom)

    def walk_delete_effect(self, eff: DeleteEffect) -> str:
        return f"(not {self.walk(eff.atom)})"

    def walk_and_effect(self, eff: AndEffect) -> str:
        return _app("and", (self.walk(e) for e in eff.effects))

    def walk_when_effect(self, eff: WhenEffect) -> str:
        return f"(when {self.walk(eff.condition)} {self.walk(eff.effect)})"

    def walk_forall_effect(self, eff: ForallEffect) -> str:
        return f"(forall ({_typed(eff.variables)}) {self.walk(eff.effect)})"

    def walk_numeric_effect(self, eff: NumericEffect) -> str:
        return f"({eff.op} {self.walk(eff.fluent)} {self.walk(eff.value)})"


_WRITER = PddlWriter()


def write_num_expr(expr: NumExpr) -> str:
    return _WRITER.walk(expr)


def write_condition(cond: Condition) -> str:
    return _WRITER.walk(cond)


def write_effect(eff: Effect) -> str:
    return _WRITER.walk(eff)


def write_fluent_value(value: FluentValue) -> str:
    return f"(= {write_num_expr(value.fluent)} {write_number(value.value)})"


def _skeleton(item: PredicateDef | FunctionDef) -> str:
    params = _typed(item.parameters)
    return f"({item.name}{' ' + params if params else ''})"


def _action(action: Action | DurativeAction) -> str:
    lines = [f"  (:{'action' if isinstance(action, Action) else 'durative-action'} {action.name}"]
    lines.append(f"    :parameters ({_typed(action.parameters)})")
    if isinstance(action, Action):
        if action.precondition != TRUE:
            lines.append(f"    :precondition {write_condition(action.precondition)}")
        if action.effect != AndEffect(()):
            lines.append(f"    :effect {write_effect(action.effect)}")
    else:
        constraints = [f"({c.op} ?duration {write_num_expr(c.value)})" for c in action.duration]
        if len(constraints) == 1:
            lines.append(f"    :duration {constraints[0]}")
        elif constraints:
            lines.append(f"    :duration (and {' '.join(constraints)})")
        conds = [
            f"({when} {write_condition(c)})"
            for when, c in (
                ("at start", action.at_start),
                ("over all", action.over_all),
                ("at end", action.at_end),
            )
            if c != TRUE
        ]
        if conds:
            lines.append("    :condition (and\n      " + "\n      ".join(conds) + ")")
        effects = [
            f"({when} {write_effect(e)})"
            for when, e in (("at start", action.start_effect), ("at end", action.end_effect))
            if e != AndEffect(())
        ]
        if effects:
            lines.append("    :effect (and\n      " + "\n      ".join(effects) + ")")
    return "\n".join(lines) + ")"


def _derived(derived: DerivedPredicate) -> str:
    return f"  (:derived {_skeleton(derived.head)}\n    {write_condition(derived.condition)})"


def _section(keyword: str, items: list[str]) -> str:
    if not items:
        return f"  ({keyword})"
    return f"  ({keyword}\n    " + "\n    ".join(items) + ")"


def write_domain(domain: Domain) -> str:
    parts = [f"(define (domain {domain.name})"]
    if domain.requirements:
        parts.append(f"  (:requirements {' '.join(domain.requirements)})")
    if domain.types:
        parts.append(_section(":types", [f"{t.name} - {_types(t.parents)}" for t in domain.types]))
    if domain.constants:
        parts.append(_section(":constants", [_typed([c]) for c in domain.constants]))
    if domain.predicates:
        parts.append(_section(":predicates", [_skeleton(p) for p in domain.predicates]))
    if domain.functions:
        parts.append(
            _section(":functions", [f"{_skeleton(f)} - {f.return_type}" for f in domain.functions])
        )
    parts.extend(_derived(d) for d in domain.derived)
    parts.extend(_action(a) for a in domain.actions)
    return "\n".join(parts) + "\n)\n"


def _metric(metric: Metric) -> str:
    expr = metric.expression
    text = "(total-time)" if expr == "total-time" else write_num_expr(expr)
    return f"  (:metric {metric.direction} {text})"


def write_problem(problem: Problem) -> str:
    parts = [f"(define (problem {problem.name})", f"  (:domain {problem.domain_name})"]
    if problem.requirements:
        parts.append(f"  (:requirements {' '.join(problem.requirements)})")
    parts.append(_section(":objects", [_typed([o]) for o in problem.objects]))
    parts.append(
        _section(
            ":init",
            [write_atom(a) for a in problem.init]
            + [write_fluent_value(v) for v in problem.init_fluents],
        )
    )
    parts.append(f"  (:goal {write_condition(problem.goal)})")
    if problem.metric is not None:
        parts.append(_metric(problem.metric))
    return "\n".join(parts) + "\n)\n"
