"""Turns lark's LALR reductions straight into model objects.

The builder is handed to lark as an *inline* transformer, so no parse tree is ever
built: each reduction calls one method here with its children (lark ``Token``s for
terminals, model objects for sub-rules). Only tokens carry positions; the builder
copies them into ``SourceLocation``s on the nodes the model keeps locations for.
Structural mistakes that the grammar lets through on purpose (to keep it LALR and
small) are reported here as ``PddlSyntaxError`` with the offending token's place.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

from lark import Token, Transformer

from plansys_bridge.errors import PddlSyntaxError, SourceLocation
from plansys_bridge.pddl.model import (
    NO_EFFECT,
    NUMBER_TYPE,
    OBJECT_TYPE,
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
    DurationConstraint,
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
    TypeDef,
    TypedName,
    WhenEffect,
)

Children = list[Any]

_OBJECT = (OBJECT_TYPE,)
_TIME_SLOTS = {"at start": "start", "at end": "end", "over all": "all"}


class TypeSpec:
    """``- type`` or ``- (either a b)`` inside a typed list."""

    __slots__ = ("token", "types")

    def __init__(self, types: tuple[str, ...], token: Token) -> None:
        self.types = types
        self.token = token


class Timed:
    """A condition or effect under ``at start`` / ``over all`` / ``at end``."""

    __slots__ = ("slot", "token", "value")

    def __init__(self, slot: str, value: Any, token: Token) -> None:
        self.slot = slot
        self.value = value
        self.token = token


def combine_conditions(items: Sequence[Condition]) -> Condition:
    """One condition as itself, several as their conjunction, none as TRUE."""
    if not items:
        return TRUE
    if len(items) == 1:
        return items[0]
    return And(tuple(items))


def combine_effects(items: Sequence[Effect]) -> Effect:
    if not items:
        return NO_EFFECT
    if len(items) == 1:
        return items[0]
    return AndEffect(tuple(items))


def _flatten_timed(children: Iterable[Any]) -> list[Timed]:
    out: list[Timed] = []
    for child in children:
        if isinstance(child, Timed):
            out.append(child)
        elif isinstance(child, list):
            out.extend(child)
    return out


class Builder(Transformer[Token, Any]):
    """Inline transformer; ``file`` is set by the parser before each parse."""

    def __init__(self) -> None:
        super().__init__(visit_tokens=False)
        self.file = "<pddl>"

    # ------------------------------------------------------------ helpers

    def loc(self, tok: Token) -> SourceLocation:
        return SourceLocation(self.file, tok.line or 0, tok.column or 0)

    def error(self, message: str, tok: Token) -> PddlSyntaxError:
        return PddlSyntaxError(message, self.loc(tok))

    def number(self, tok: Token) -> float:
        """A NUMBER token's value; one too large for a float (``1e999``) is an error."""
        value = float(tok.value)
        if not math.isfinite(value):
            raise self.error(f"number {tok.value} is out of range", tok)
        return value

    def typed(self, items: Iterable[Any], where: Token | None = None) -> tuple[TypedName, ...]:
        """Group ``a b - t c`` into typed names (untyped ones are ``object``)."""
        out: list[TypedName] = []
        pending: list[Token] = []
        file = self.file
        for item in items:
            if isinstance(item, TypeSpec):
                if not pending:
                    raise self.error("'-' type without names before it", item.token)
                types = item.types
                for tok in pending:
                    out.append(
                        TypedName(
                            tok.value, types, SourceLocation(file, tok.line or 0, tok.column or 0)
                        )
                    )
                pending = []
            else:
                pending.append(item)
        for tok in pending:
            out.append(
                TypedName(tok.value, _OBJECT, SourceLocation(file, tok.line or 0, tok.column or 0))
            )
        return tuple(out)

    def num(self, value: Any) -> NumExpr:
        """Convert a bare token inside a numeric expression."""
        if isinstance(value, Token):
            kind = value.type
            if kind == "NUMBER":
                return Number(self.number(value))
            if kind == "NAME":
                return FluentRef(value.value, (), self.loc(value))
            if value.value == "?duration":
                return DurationRef()
            raise self.error(
                f"variable {value.value} used as a number (only ?duration is numeric)", value
            )
        result: NumExpr = value
        return result

    # ------------------------------------------------------------ declarations

    def type_sep(self, c: Children) -> TypeSpec:
        spec = c[1]
        types = spec if isinstance(spec, tuple) else (spec.value,)
        return TypeSpec(types, c[0])

    def either(self, c: Children) -> tuple[str, ...]:
        return tuple(t.value for t in c)

    def requirements(self, c: Children) -> tuple[str, Any]:
        return ("requirements", tuple(t.value for t in c))

    def types(self, c: Children) -> tuple[str, Any]:
        return ("types", [TypeDef(t.name, t.types, t.loc) for t in self.typed(c)])

    def constants(self, c: Children) -> tuple[str, Any]:
        return ("constants", list(self.typed(c)))

    def skeleton(self, c: Children) -> tuple[Token, tuple[TypedName, ...]]:
        return (c[0], self.typed(c[1:]))

    def predicates(self, c: Children) -> tuple[str, Any]:
        return ("predicates", [PredicateDef(tok.value, params, self.loc(tok)) for tok, params in c])

    def functions(self, c: Children) -> tuple[str, Any]:
        out: list[FunctionDef] = []
        pending: list[tuple[Token, tuple[TypedName, ...]]] = []
        for item in c:
            if isinstance(item, TypeSpec):
                if not pending:
                    raise self.error("'-' return type without functions before it", item.token)
                if len(item.types) != 1:
                    raise self.error("a function returns one type, not 'either'", item.token)
                ret = item.types[0]
                out.extend(FunctionDef(t.value, p, ret, self.loc(t)) for t, p in pending)
                pending = []
            else:
                pending.append(item)
        out.extend(FunctionDef(t.value, p, NUMBER_TYPE, self.loc(t)) for t, p in pending)
        return ("functions", out)

    def derived(self, c: Children) -> tuple[str, Any]:
        tok, params = c[0]
        loc = self.loc(tok)
        return ("derived", DerivedPredicate(PredicateDef(tok.value, params, loc), c[1], loc))

    # ------------------------------------------------------------ actions

    def parameters(self, c: Children) -> tuple[str, Any]:
        return ("parameters", self.typed(c))

    def precondition(self, c: Children) -> tuple[str, Any]:
        return ("precondition", c[0])

    def effect_part(self, c: Children) -> tuple[str, Any]:
        return ("effect", c[0])

    def _parts(self, name: Token, parts: Children) -> dict[str, Any]:
        seen: dict[str, Any] = {}
        for key, value in parts:
            if key in seen:
                raise self.error(f"action '{name.value}' has two :{key} sections", name)
            seen[key] = value
        return seen

    def action(self, c: Children) -> tuple[str, Any]:
        name = c[0]
        parts = self._parts(name, c[1:])
        return (
            "action",
            Action(
                name.value,
                parts.get("parameters", ()),
                parts.get("precondition", TRUE),
                parts.get("effect", NO_EFFECT),
                self.loc(name),
            ),
        )

    def simple_dc(self, c: Children) -> DurationConstraint:
        op, var, value = c
        if var.value != "?duration":
            raise self.error(f"expected ?duration, found {var.value}", var)
        if op.value not in ("=", "<=", ">="):
            raise self.error(f"duration constraints use =, <= or >=, not {op.value}", op)
        return DurationConstraint(op.value, self.num(value))

    def duration(self, c: Children) -> tuple[str, Any]:
        return ("duration", tuple(c))

    def timed_gd(self, c: Children) -> Timed:
        tok = c[0]
        return Timed(_TIME_SLOTS[" ".join(tok.value.split())], c[1], tok)

    def da_forall(self, c: Children) -> list[Timed]:
        timed = _flatten_timed(c)
        variables = self.typed(x for x in c if isinstance(x, Token | TypeSpec))
        return [Timed(t.slot, Forall(variables, t.value), t.token) for t in timed]

    def da_condition(self, c: Children) -> tuple[str, Any]:
        return ("condition", _flatten_timed(c))

    def timed_effect(self, c: Children) -> Timed:
        tok = c[0]
        slot = _TIME_SLOTS[" ".join(tok.value.split())]
        if slot == "all":
            raise self.error("effects happen 'at start' or 'at end', not 'over all'", tok)
        return Timed(slot, c[1], tok)

    def da_effect_forall(self, c: Children) -> list[Timed]:
        timed = _flatten_timed(c)
        variables = self.typed(x for x in c if isinstance(x, Token | TypeSpec))
        return [Timed(t.slot, ForallEffect(variables, t.value), t.token) for t in timed]

    def da_effect_part(self, c: Children) -> tuple[str, Any]:
        return ("effect", _flatten_timed(c))

    def durative_action(self, c: Children) -> tuple[str, Any]:
        name = c[0]
        parts = self._parts(name, c[1:])
        conds: dict[str, list[Condition]] = {"start": [], "all": [], "end": []}
        for t in parts.get("condition", ()):
            conds[t.slot].append(t.value)
        effects: dict[str, list[Effect]] = {"start": [], "end": []}
        for t in parts.get("effect", ()):
            effects[t.slot].append(t.value)
        return (
            "action",
            DurativeAction(
                name.value,
                parts.get("parameters", ()),
                parts.get("duration", ()),
                combine_conditions(conds["start"]),
                combine_conditions(conds["all"]),
                combine_conditions(conds["end"]),
                combine_effects(effects["start"]),
                combine_effects(effects["end"]),
                self.loc(name),
            ),
        )

    def domain(self, c: Children) -> Domain:
        name = c[0]
        sections: dict[str, list[Any]] = {
            "requirements": [],
            "types": [],
            "constants": [],
            "predicates": [],
            "functions": [],
            "action": [],
            "derived": [],
        }
        for key, value in c[1:]:
            if key in ("action", "derived"):
                sections[key].append(value)
            else:
                sections[key].extend(value)
        return Domain(
            name.value,
            tuple(dict.fromkeys(sections["requirements"])),
            tuple(sections["types"]),
            tuple(sections["constants"]),
            tuple(sections["predicates"]),
            tuple(sections["functions"]),
            tuple(sections["action"]),
            tuple(sections["derived"]),
            self.file,
        )

    # ------------------------------------------------------------ conditions

    def atom(self, c: Children) -> Atom:
        tok = c[0]
        return Atom(
            tok.value,
            tuple([t.value for t in c[1:]]),
            SourceLocation(self.file, tok.line or 0, tok.column or 0),
        )

    def empty_gd(self, c: Children) -> Condition:
        return TRUE

    def and_gd(self, c: Children) -> Condition:
        return And(tuple(c))

    def or_gd(self, c: Children) -> Condition:
        return Or(tuple(c))

    def not_gd(self, c: Children) -> Condition:
        return Not(c[0])

    def imply_gd(self, c: Children) -> Condition:
        return Imply(c[0], c[1])

    def exists_gd(self, c: Children) -> Condition:
        return Exists(self.typed(c[:-1]), c[-1])

    def forall_gd(self, c: Children) -> Condition:
        return Forall(self.typed(c[:-1]), c[-1])

    def comparison(self, c: Children) -> Condition:
        op, left, right = c
        if (
            op.value == "="
            and isinstance(left, Token)
            and isinstance(right, Token)
            and left.type != "NUMBER"
            and right.type != "NUMBER"
            and left.value != "?duration"
            and right.value != "?duration"
        ):
            return Equals(left.value, right.value)
        return Compare(op.value, self.num(left), self.num(right))

    # ------------------------------------------------------------ numeric expressions

    def f_head(self, c: Children) -> FluentRef:
        tok = c[0]
        return FluentRef(tok.value, tuple([t.value for t in c[1:]]), self.loc(tok))

    def f_arith(self, c: Children) -> NumExpr:
        op = c[0]
        operands = [self.num(x) for x in c[1:]]
        if len(operands) == 1:
            if op.value == "-":
                return Negate(operands[0])
            raise self.error(f"'{op.value}' needs two operands", op)
        if len(operands) > 2 and op.value in ("-", "/"):
            raise self.error(f"'{op.value}' takes exactly two operands", op)
        result = operands[0]
        for operand in operands[1:]:
            result = BinaryOp(op.value, result, operand)
        return result

    # ------------------------------------------------------------ effects

    def add_effect(self, c: Children) -> Effect:
        return AddEffect(c[0])

    def delete_effect(self, c: Children) -> Effect:
        return DeleteEffect(c[0])

    def empty_effect(self, c: Children) -> Effect:
        return NO_EFFECT

    def and_effect(self, c: Children) -> Effect:
        return AndEffect(tuple(c))

    def forall_effect(self, c: Children) -> Effect:
        return ForallEffect(self.typed(c[:-1]), c[-1])

    def when_effect(self, c: Children) -> Effect:
        return WhenEffect(c[0], c[1])

    def numeric_effect(self, c: Children) -> Effect:
        return NumericEffect(c[0].value, c[1], self.num(c[2]))

    # ------------------------------------------------------------ problem

    def problem_domain(self, c: Children) -> tuple[str, Any]:
        return ("domain", c[0].value if c else "")

    def objects(self, c: Children) -> tuple[str, Any]:
        return ("objects", self.typed(c))

    def init_fluent(self, c: Children) -> FluentValue:
        op, ref, value = c
        if op.value != "=":
            raise self.error(f"initial values are set with '=', not '{op.value}'", op)
        return FluentValue(ref, self.number(value))

    def init(self, c: Children) -> tuple[str, Any]:
        return ("init", c)

    def goal(self, c: Children) -> tuple[str, Any]:
        return ("goal", c[0])

    def metric(self, c: Children) -> tuple[str, Any]:
        direction, expr = c
        value = self.num(expr)
        if isinstance(value, FluentRef) and value.name == "total-time" and not value.args:
            return ("metric", Metric(direction.value, "total-time"))
        return ("metric", Metric(direction.value, value))

    def problem(self, c: Children) -> Problem:
        name = c[0]
        fields: dict[str, Any] = {}
        requirements: list[str] = []
        objects: list[TypedName] = []
        atoms: list[Atom] = []
        fluents: list[FluentValue] = []
        for key, value in c[1:]:
            if key == "requirements":
                requirements.extend(value)
            elif key == "objects":
                objects.extend(value)
            elif key == "init":
                for item in value:
                    (atoms if type(item) is Atom else fluents).append(item)
            elif key in fields:
                raise self.error(f"problem '{name.value}' has two :{key} sections", name)
            else:
                fields[key] = value
        return Problem(
            name.value,
            fields.get("domain", ""),
            tuple(dict.fromkeys(requirements)),
            tuple(objects),
            tuple(atoms),
            tuple(fluents),
            fields.get("goal", TRUE),
            fields.get("metric"),
            self.file,
        )

    # ------------------------------------------------------------ entry points

    def condition_entry(self, c: Children) -> Any:
        return c[0]

    effect_entry = atom_entry = fluent_value_entry = condition_entry
