"""Substituting objects for variables, and the ground action the executor runs.

Why substitution produces new model nodes instead of carrying bindings around: a
ground action's conditions are then self-contained (they print as PDDL, compare and
hash), so the plan graph, the validator and the monitor can share them freely.
Quantified variables are left alone (an inner ``?x`` shadows an outer one).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

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
    FluentRef,
    Not,
    Number,
    NumericEffect,
    NumExpr,
    WhenEffect,
)
from plansys_bridge.pddl.walkers import Transformer, bound_variables


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
    """Replace variables by their objects; an unbound variable is an error naming it.

    This runs for every atom of every condition and effect evaluated, so: a ground
    tuple with no bindings (the executor's ground actions) is handed back as it is,
    and otherwise a list comprehension, not a generator (each generator step is a
    call of its own)."""
    if not bindings and args.__class__ is tuple:
        for a in args:
            if a[:1] == "?":
                raise UnboundVariableError(f"variable {a} is not bound")
        return args
    try:
        return tuple([bindings[a] if a[:1] == "?" else a for a in args])
    except KeyError as exc:
        raise UnboundVariableError(f"variable {exc.args[0]} is not bound") from None


def effect_facts(effect: Effect) -> tuple[list[Atom], list[Atom]] | None:
    """``(adds, deletes)``, the effect's own atoms, when it only adds and deletes
    ground atoms; None for any other effect. A variable raises as grounding it
    without bindings does, the first in the order the general walk takes.

    Why the atoms as written (their source location too): the knowledge base only
    reads their predicate and arguments, to find the facts it admitted before
    (:meth:`Admission.facts`), so copying them would be wasted work."""
    parts = effect.effects if effect.__class__ is AndEffect else (effect,)
    adds: list[Atom] = []
    deletes: list[Atom] = []
    for part in parts:
        if part.__class__ is AddEffect:
            found = adds
        elif part.__class__ is DeleteEffect:
            found = deletes
        else:
            return None
        atom = part.atom
        if atom.args.__class__ is not tuple:
            return None  # grounding makes it a tuple: left to the general walk
        for arg in atom.args:
            if arg[:1] == "?":
                raise UnboundVariableError(f"variable {arg} is not bound")
        found.append(atom)
    return adds, deletes


def _sub_args(args: tuple[str, ...], b: Mapping[str, str]) -> tuple[str, ...]:
    # a list comprehension: a generator is resumed (a call) once per argument
    return tuple([b.get(a, a) if a[:1] == "?" else a for a in args])


class _Substitute(Transformer):
    """Replaces bound variables; a quantifier's own variables shadow outer bindings."""

    def __init__(self, bindings: Mapping[str, str]) -> None:
        self.b = bindings

    def term(self, term: str) -> str:
        return self.b.get(term, term) if term[:1] == "?" else term

    def default(self, node: Any, *args: Any) -> Any:
        names = bound_variables(node)
        if names and not self.b.keys().isdisjoint(names):
            inner = {k: v for k, v in self.b.items() if k not in names}
            return _Substitute(inner).rebuild(node) if inner else node
        return self.rebuild(node)

    # Fast paths: every ground action's conditions and effects go through these.
    def walk(self, node: Any, *args: Any) -> Any:
        fn = self._methods.get(node.__class__)
        if fn is None:
            fn = self.method_for(node.__class__)
        return fn(self, node)

    def walk_atom(self, atom: Atom) -> Atom:
        b = self.b  # _sub_args, inlined (every atom of every ground action)
        return Atom(
            atom.predicate, tuple([b.get(a, a) if a[:1] == "?" else a for a in atom.args]), atom.loc
        )

    def walk_fluent_ref(self, ref: FluentRef) -> FluentRef:
        return FluentRef(ref.name, _sub_args(ref.args, self.b), ref.loc)

    def walk_and(self, cond: And) -> And:
        # an atom straight to walk_atom: no dispatch (two calls) per atom
        return And(
            tuple(
                [self.walk_atom(c) if c.__class__ is Atom else self.walk(c) for c in cond.operands]
            )
        )

    def walk_not(self, cond: Not) -> Not:
        return Not(self.walk(cond.operand))

    def walk_compare(self, cond: Compare) -> Compare:
        return Compare(cond.op, self.walk(cond.left), self.walk(cond.right))

    def walk_binary_op(self, expr: BinaryOp) -> BinaryOp:
        return BinaryOp(expr.op, self.walk(expr.left), self.walk(expr.right))

    def walk_when_effect(self, eff: WhenEffect) -> WhenEffect:
        return WhenEffect(self.walk(eff.condition), self.walk(eff.effect))

    def walk_add_effect(self, eff: AddEffect) -> AddEffect:
        return AddEffect(self.walk_atom(eff.atom))

    def walk_delete_effect(self, eff: DeleteEffect) -> DeleteEffect:
        return DeleteEffect(self.walk_atom(eff.atom))

    def walk_and_effect(self, eff: AndEffect) -> AndEffect:
        # adds and deletes without the dispatch, as in walk_and
        return AndEffect(
            tuple(
                [
                    AddEffect(self.walk_atom(e.atom))
                    if e.__class__ is AddEffect
                    else DeleteEffect(self.walk_atom(e.atom))
                    if e.__class__ is DeleteEffect
                    else self.walk(e)
                    for e in eff.effects
                ]
            )
        )

    def walk_numeric_effect(self, eff: NumericEffect) -> NumericEffect:
        return NumericEffect(eff.op, self.walk_fluent_ref(eff.fluent), self.walk(eff.value))


def substitute_expr(expr: NumExpr, b: Mapping[str, str]) -> NumExpr:
    result: NumExpr = _Substitute(b).walk(expr)
    return result


def substitute_condition(cond: Condition, b: Mapping[str, str]) -> Condition:
    """``cond`` with bound variables replaced; unbound ones are kept as variables."""
    if not b:
        return cond
    result: Condition = _Substitute(b).walk(cond)
    return result


def substitution(b: Mapping[str, str]) -> Callable[[Any], Any]:
    """A function replacing ``b``'s variables in a condition, effect or expression:
    ``substitute_condition`` and ``substitute_effect`` for several nodes with the
    same bindings (a ground action's five) at the cost of one."""
    if not b:
        return _unchanged
    return _Substitute(b).walk


def _unchanged(node: Any) -> Any:
    return node


def substitute_effect(effect: Effect, b: Mapping[str, str]) -> Effect:
    """``effect`` with bound variables replaced."""
    if not b:
        return effect
    result: Effect = _Substitute(b).walk(effect)
    return result


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
    "effect_facts",
    "ground_args",
    "ground_term",
    "normalize_bindings",
    "substitute_condition",
    "substitute_effect",
    "substitute_expr",
    "substitution",
]
