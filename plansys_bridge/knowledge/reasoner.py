"""What conditions, numeric expressions and effects mean in a state.

Why three visitors (:mod:`plansys_bridge.pddl.walkers`) over one domain's join
solver: each construct's meaning is one method, a quantifier is solved as a join
(:mod:`.joins`) and derived predicates come from their fixpoint (:mod:`.derived`),
cached on the state snapshot. A construct with no method of its own is evaluated
as its ``lower()`` form. Atoms, by far the most frequent node, are tested before
any dispatch.

Effects follow PDDL: every condition and value is read in the old state, deletes
are applied before adds, increases on one fluent accumulate (the evaluator does
the arithmetic on what :meth:`Reasoner._collect` gathers).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from plansys_bridge.knowledge.context import EvalContext, EvaluationError, UndefinedFluentError
from plansys_bridge.knowledge.derived import DerivedRules
from plansys_bridge.knowledge.formulas import compare, describe_expr, negate
from plansys_bridge.knowledge.grounding import ground_args
from plansys_bridge.knowledge.joins import CACHE_LIMIT, JoinSolver
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
    Domain,
    DurationRef,
    Effect,
    Equals,
    Exists,
    FluentRef,
    Forall,
    ForallEffect,
    Negate,
    Not,
    Number,
    NumericEffect,
    NumExpr,
    Or,
    WhenEffect,
)
from plansys_bridge.pddl.types import TypeHierarchy
from plansys_bridge.pddl.walkers import Visitor

__all__ = ["Changes", "Reasoner"]

Bindings = Mapping[str, str]


class _Truth(Visitor[bool]):
    """Does a condition hold (``walk(cond, bindings, ctx)``)?"""

    kinds = ("condition",)

    def __init__(self, reasoner: Reasoner) -> None:
        self.r = reasoner
        self._negated: dict[int, tuple[Forall, Condition]] = {}

    # The hot path: fixed arguments (no packing), atoms tested before any dispatch,
    # conjunctions and disjunctions test their atoms in line.
    def walk(self, node: Any, b: Bindings, ctx: EvalContext) -> bool:
        cls = node.__class__
        if cls is Atom:
            return ground_args(node.args, b) in ctx.tuples(node.predicate)
        fn = self._methods.get(cls)
        if fn is None:
            fn = self.method_for(cls)
        result: bool = fn(self, node, b, ctx)
        return result

    def walk_atom(self, cond: Atom, b: Bindings, ctx: EvalContext) -> bool:
        return ground_args(cond.args, b) in ctx.tuples(cond.predicate)

    def walk_and(self, cond: And, b: Bindings, ctx: EvalContext) -> bool:
        for c in cond.operands:
            if c.__class__ is Atom:
                if ground_args(c.args, b) not in ctx.tuples(c.predicate):
                    return False
            elif not self.walk(c, b, ctx):
                return False
        return True

    def walk_or(self, cond: Or, b: Bindings, ctx: EvalContext) -> bool:
        for c in cond.operands:
            if c.__class__ is Atom:
                if ground_args(c.args, b) in ctx.tuples(c.predicate):
                    return True
            elif self.walk(c, b, ctx):
                return True
        return False

    def walk_not(self, cond: Not, b: Bindings, ctx: EvalContext) -> bool:
        return not self.walk(cond.operand, b, ctx)

    def walk_compare(self, cond: Compare, b: Bindings, ctx: EvalContext) -> bool:
        value = self.r._value
        return compare(cond.op, value(cond.left, b, ctx), value(cond.right, b, ctx))

    def walk_equals(self, cond: Equals, b: Bindings, ctx: EvalContext) -> bool:
        left, right = ground_args((cond.left, cond.right), b)
        return left == right

    def walk_imply(self, cond: Any, b: Bindings, ctx: EvalContext) -> bool:
        return not self.walk(cond.antecedent, b, ctx) or self.walk(cond.consequent, b, ctx)

    def walk_exists(self, cond: Exists, b: Bindings, ctx: EvalContext) -> bool:
        inner, var_types = self.r._scope(cond.variables, b)
        return next(self.r._solve(cond.body, inner, var_types, ctx), None) is not None

    def walk_forall(self, cond: Forall, b: Bindings, ctx: EvalContext) -> bool:
        inner, var_types = self.r._scope(cond.variables, b)
        entry = self._negated.get(id(cond))
        if entry is None or entry[0] is not cond:
            if len(self._negated) > CACHE_LIMIT:
                self._negated.clear()
            entry = self._negated[id(cond)] = (cond, negate(cond.body))
        return next(self.r._solve(entry[1], inner, var_types, ctx), None) is None


class _Value(Visitor[float]):
    """The value of a numeric expression (``walk(expr, bindings, ctx)``)."""

    kinds = ("expression",)

    def walk(self, node: Any, b: Bindings, ctx: EvalContext) -> float:
        cls = node.__class__
        if cls is Number:
            value: float = node.value
            return value
        fn = self._methods.get(cls)
        if fn is None:
            fn = self.method_for(cls)
        result: float = fn(self, node, b, ctx)
        return result

    def walk_number(self, expr: Number, b: Bindings, ctx: EvalContext) -> float:
        return expr.value

    def walk_fluent_ref(self, ref: FluentRef, b: Bindings, ctx: EvalContext) -> float:
        args = ground_args(ref.args, b)
        val = ctx.state.value(ref.name, args)
        if val is None:
            raise UndefinedFluentError(ref.name, args)
        return val

    def walk_binary_op(self, op: BinaryOp, b: Bindings, ctx: EvalContext) -> float:
        left = self.walk(op.left, b, ctx)
        right = self.walk(op.right, b, ctx)
        if op.op == "+":
            return left + right
        if op.op == "-":
            return left - right
        if op.op == "*":
            return left * right
        if right == 0:
            raise EvaluationError(f"division by zero in {describe_expr(op)}")
        return left / right

    def walk_negate(self, expr: Negate, b: Bindings, ctx: EvalContext) -> float:
        return -self.walk(expr.operand, b, ctx)

    def walk_duration_ref(self, expr: DurationRef, b: Bindings, ctx: EvalContext) -> float:
        if ctx.duration is None:
            raise EvaluationError("?duration used where no duration is known")
        return ctx.duration


class Changes:
    """What an effect does, gathered in the old state: adds, deletes, numeric updates."""

    __slots__ = ("adds", "deletes", "numeric")

    def __init__(self) -> None:
        self.adds: list[Atom] = []
        self.deletes: list[Atom] = []
        self.numeric: list[tuple[str, FluentKey, float]] = []


class _Effects(Visitor[None]):
    """Gathers an effect's changes (``walk(effect, bindings, ctx, changes)``)."""

    kinds = ("effect",)

    def __init__(self, reasoner: Reasoner) -> None:
        self.r = reasoner

    def walk(self, node: Any, b: Bindings, ctx: EvalContext, out: Changes) -> None:
        fn = self._methods.get(node.__class__)
        if fn is None:
            fn = self.method_for(node.__class__)
        fn(self, node, b, ctx, out)

    def walk_and_effect(self, eff: AndEffect, b: Bindings, ctx: EvalContext, out: Changes) -> None:
        methods = self._methods  # dispatch in line: most effects are parts of an ``and``
        for sub in eff.effects:
            fn = methods.get(sub.__class__)
            if fn is None:
                fn = self.method_for(sub.__class__)
            fn(self, sub, b, ctx, out)

    def walk_add_effect(self, eff: AddEffect, b: Bindings, ctx: EvalContext, out: Changes) -> None:
        out.adds.append(Atom(eff.atom.predicate, ground_args(eff.atom.args, b)))

    def walk_delete_effect(
        self, eff: DeleteEffect, b: Bindings, ctx: EvalContext, out: Changes
    ) -> None:
        out.deletes.append(Atom(eff.atom.predicate, ground_args(eff.atom.args, b)))

    def walk_numeric_effect(
        self, eff: NumericEffect, b: Bindings, ctx: EvalContext, out: Changes
    ) -> None:
        key = (eff.fluent.name, ground_args(eff.fluent.args, b))
        out.numeric.append((eff.op, key, self.r._value(eff.value, b, ctx)))

    def walk_when_effect(
        self, eff: WhenEffect, b: Bindings, ctx: EvalContext, out: Changes
    ) -> None:
        if self.r._holds(eff.condition, b, ctx):
            self.walk(eff.effect, b, ctx, out)

    def walk_forall_effect(
        self, eff: ForallEffect, b: Bindings, ctx: EvalContext, out: Changes
    ) -> None:
        inner, var_types = self.r._scope(eff.variables, b)
        body = eff.effect
        if isinstance(body, WhenEffect):
            # Let the condition drive the grounding instead of every combination.
            for nb in self.r._solve(body.condition, inner, var_types, ctx):
                self.walk(body.effect, nb, ctx, out)
        else:
            for nb in self.r._bind_rest(inner, list(var_types), var_types, ctx):
                self.walk(body, nb, ctx, out)


class Reasoner(JoinSolver):
    """One domain's conditions, values and effects evaluated against states."""

    def __init__(self, domain: Domain) -> None:
        super().__init__(TypeHierarchy(domain))
        self.domain = domain
        self._derived = DerivedRules(domain)
        self._derived_rules = self._derived.rules
        self._strata = self._derived.strata
        # Bound walk methods, not wrappers: one call less per node on the hot path.
        self._holds = _Truth(self).walk
        self._value: Callable[[NumExpr, Bindings, EvalContext], float] = _Value().walk
        self._collect: Callable[[Effect, Bindings, EvalContext, Changes], None]
        self._collect = _Effects(self).walk

    def _derived_table(self, state: State) -> dict[str, frozenset[Args]]:
        cache = state.cache()
        key = (id(self), "derived")
        table = cache.get(key)
        if table is None:
            table = self._derived.compute(self, self, state)
            cache[key] = table
        return table

    def _context(self, state: State, duration: float | None = None) -> EvalContext:
        return EvalContext(self, state, duration)

    def _constants_state(self) -> State:
        return State(objects={c.name: c.types[0] for c in self.domain.constants})
