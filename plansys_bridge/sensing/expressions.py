"""The small expression language of sensing rules, parsed with lark (never ``eval``).

A rule's ``when``, ``clear_when`` and value are texts such as
``battery_remaining < 25 and voltage_battery > 0`` or ``current_battery / 100``:
comparisons, ``and``/``or``/``not``, ``+ - * / %``, numbers, quoted strings,
``true``/``false`` and field names (dotted and indexed for nested message fields:
``pose.pose.position.x``, ``voltages[0]``). The grammar (``grammar.lark``, shipped
with the package) admits nothing else, so a rule cannot call a function or reach
an attribute of the program; a text that does not parse is an error naming the
column. Parsed expressions know the fields they read, so a rule naming a field the
message does not have is refused when the mission loads, not when the message comes.
"""

from __future__ import annotations

import math
import operator
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import resources
from typing import Any

from lark import Lark, Token, Transformer, UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from plansys_bridge.errors import PlansysBridgeError

__all__ = ["Expression", "ExpressionError", "Sample", "parse_expression"]

Sample = Mapping[str, Any]
"""One message's values by field path (``battery_remaining``, ``pose.position.x``)."""

Value = float | bool | str


class ExpressionError(PlansysBridgeError):
    """A rule text that does not parse, or a value it cannot compute from a sample.

    ``column`` is 1-based within the text (None when the problem is not at one place).
    """

    def __init__(self, message: str, column: int | None = None) -> None:
        self.message = message
        self.column = column
        super().__init__(f"column {column}: {message}" if column is not None else message)


class _Node:
    """One node of a parsed expression."""

    def value(self, sample: Sample) -> Value:
        raise NotImplementedError

    def fields(self) -> set[str]:
        return set()


@dataclass(frozen=True)
class _Const(_Node):
    constant: Value

    def value(self, sample: Sample) -> Value:
        return self.constant


@dataclass(frozen=True)
class _Field(_Node):
    path: str
    column: int

    def value(self, sample: Sample) -> Value:
        try:
            found = sample[self.path]
        except KeyError:
            raise ExpressionError(f"the message has no field {self.path!r}", self.column) from None
        if isinstance(found, bool | str):
            return found
        if isinstance(found, int | float):
            return float(found)
        if isinstance(found, bytes):
            return found.decode("utf-8", "replace").rstrip("\0")
        raise ExpressionError(
            f"field {self.path!r} is {type(found).__name__}, not a number or text", self.column
        )

    def fields(self) -> set[str]:
        return {self.path}


def _number(value: Value, what: str, column: int) -> float:
    if isinstance(value, bool) or not isinstance(value, float):
        raise ExpressionError(f"{what} needs numbers, got {value!r}", column)
    return value


_ARITH: dict[str, Callable[[float, float], float]] = {
    "+": operator.add,
    "-": operator.sub,
    "*": operator.mul,
    "/": operator.truediv,
    "%": operator.mod,
}
_COMPARE: dict[str, Callable[[Any, Any], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
    "==": operator.eq,
    "!=": operator.ne,
}


@dataclass(frozen=True)
class _Arith(_Node):
    op: str
    left: _Node
    right: _Node
    column: int

    def value(self, sample: Sample) -> Value:
        a = _number(self.left.value(sample), f"'{self.op}'", self.column)
        b = _number(self.right.value(sample), f"'{self.op}'", self.column)
        if self.op in "/%" and b == 0:
            raise ExpressionError(f"division by zero ({a:g} {self.op} 0)", self.column)
        return _ARITH[self.op](a, b)

    def fields(self) -> set[str]:
        return self.left.fields() | self.right.fields()


@dataclass(frozen=True)
class _Neg(_Node):
    operand: _Node
    column: int

    def value(self, sample: Sample) -> Value:
        return -_number(self.operand.value(sample), "'-'", self.column)

    def fields(self) -> set[str]:
        return self.operand.fields()


@dataclass(frozen=True)
class _Compare(_Node):
    op: str
    left: _Node
    right: _Node
    column: int

    def value(self, sample: Sample) -> Value:
        a, b = self.left.value(sample), self.right.value(sample)
        if self.op in ("==", "!="):
            return _COMPARE[self.op](a, b)
        if isinstance(a, str) and isinstance(b, str):
            return _COMPARE[self.op](a, b)
        what = f"'{self.op}'"
        return _COMPARE[self.op](_number(a, what, self.column), _number(b, what, self.column))

    def fields(self) -> set[str]:
        return self.left.fields() | self.right.fields()


@dataclass(frozen=True)
class _Logic(_Node):
    op: str  # "and" / "or"
    operands: tuple[_Node, ...]

    def value(self, sample: Sample) -> Value:
        if self.op == "and":
            return all(_truth(o.value(sample)) for o in self.operands)
        return any(_truth(o.value(sample)) for o in self.operands)

    def fields(self) -> set[str]:
        return set().union(*(o.fields() for o in self.operands))


@dataclass(frozen=True)
class _Not(_Node):
    operand: _Node

    def value(self, sample: Sample) -> Value:
        return not _truth(self.operand.value(sample))

    def fields(self) -> set[str]:
        return self.operand.fields()


def _truth(value: Value) -> bool:
    """Numbers are true when non-zero (a fault bit), text when non-empty."""
    return bool(value)


def _col(token: Token) -> int:
    return token.column if token.column is not None else 1


class _Build(Transformer[Token, _Node]):
    """One method per grammar rule (aliases keep single operands: pass them through)."""

    def or_(self, items: list[_Node]) -> _Node:
        return items[0] if len(items) == 1 else _Logic("or", tuple(items))

    def and_(self, items: list[_Node]) -> _Node:
        return items[0] if len(items) == 1 else _Logic("and", tuple(items))

    def not_(self, items: list[_Node]) -> _Node:
        return _Not(items[0])

    def compare(self, items: list[Any]) -> _Node:
        if len(items) == 1:
            return items[0]
        left, op, right = items
        return _Compare(str(op), left, right, _col(op))

    def arith(self, items: list[Any]) -> _Node:
        node: _Node = items[0]
        for i in range(1, len(items), 2):
            op = items[i]
            node = _Arith(str(op), node, items[i + 1], _col(op))
        return node

    def neg(self, items: list[Any]) -> _Node:
        return _Neg(items[1], _col(items[0]))

    def pos(self, items: list[Any]) -> _Node:
        return items[1]

    def number(self, items: list[Token]) -> _Node:
        value = float(items[0])
        if not math.isfinite(value):
            raise ExpressionError(f"{items[0]} is not a finite number", _col(items[0]))
        return _Const(value)

    def string(self, items: list[Token]) -> _Node:
        return _Const(str(items[0])[1:-1])

    def field(self, items: list[Token]) -> _Node:
        return _Field(str(items[0]), _col(items[0]))

    def true(self, items: list[Token]) -> _Node:
        return _Const(True)

    def false(self, items: list[Token]) -> _Node:
        return _Const(False)


_lock = threading.Lock()
_lark: Lark | None = None

_TOKEN_WORDS = {
    "_OR": "'or'",
    "_AND": "'and'",
    "_NOT": "'not'",
    "COMP": "a comparison",
    "PLUS": "'+'",
    "MINUS": "'-'",
    "MUL": "'*', '/' or '%'",
    "FIELD": "a field name",
    "NUMBER": "a number",
    "STRING": "a quoted text",
    "LPAR": "'('",
    "RPAR": "')'",
    "$END": "the end of the text",
}


def _parser() -> Lark:
    global _lark
    with _lock:
        if _lark is None:
            grammar = resources.files(__package__).joinpath("grammar.lark").read_text("utf-8")
            _lark = Lark(grammar, parser="lalr", propagate_positions=True)
        return _lark


def _expected(exc: UnexpectedInput) -> str:
    names = sorted(getattr(exc, "expected", None) or getattr(exc, "allowed", None) or ())
    words = sorted({_TOKEN_WORDS.get(n, n.lower()) for n in names if not n.startswith("__")})
    return f" (expected {', '.join(words)})" if words else ""


@dataclass(frozen=True)
class Expression:
    """A parsed rule text: evaluate it on a sample, list the fields it reads."""

    text: str
    _root: _Node

    def value(self, sample: Sample) -> Value:
        """The value on ``sample``; ExpressionError naming the column when it cannot."""
        return self._root.value(sample)

    def holds(self, sample: Sample) -> bool:
        return _truth(self.value(sample))

    def number(self, sample: Sample) -> float:
        """The value as a finite number (a PDDL function's value)."""
        result = self.value(sample)
        if isinstance(result, bool):
            return 1.0 if result else 0.0
        if not isinstance(result, float) or not math.isfinite(result):
            raise ExpressionError(f"{self.text!r} gave {result!r}, not a finite number")
        return result

    @property
    def fields(self) -> frozenset[str]:
        return frozenset(self._root.fields())

    def __str__(self) -> str:
        return self.text


def parse_expression(text: str) -> Expression:
    """Parse a rule text; ExpressionError with the column when it is not valid."""
    if not isinstance(text, str) or not text.strip():
        raise ExpressionError("expected an expression such as 'battery_remaining < 25'")
    try:
        tree = _parser().parse(text)
        root = _Build().transform(tree)
    except UnexpectedCharacters as exc:
        raise ExpressionError(
            f"unexpected {text[exc.pos_in_stream or 0]!r}{_expected(exc)}", exc.column
        ) from None
    except UnexpectedToken as exc:
        token = exc.token
        shown = "the end of the text" if token.type == "$END" else repr(str(token))
        column = len(text) + 1 if token.type == "$END" else exc.column
        raise ExpressionError(f"unexpected {shown}{_expected(exc)}", column) from None
    except UnexpectedInput as exc:
        raise ExpressionError(f"not a valid expression{_expected(exc)}", exc.column) from None
    except Exception as exc:  # lark wraps errors raised in the transformer
        inner = getattr(exc, "orig_exc", None)
        if isinstance(inner, ExpressionError):
            raise inner from None
        raise
    return Expression(text, root)
