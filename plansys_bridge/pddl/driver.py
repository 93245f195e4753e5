"""The LALR loop: lark's parse table and callbacks, driven with our lexer in one pass.

Kept because ``benchmarks/bench_parse.py`` shows what it is worth: with lark's parse
loop in its place (our lexer kept), the same pipeline takes 1.1x to 1.5x as long on a
generated problem of 5000 objects (320-443 ms against 293-296 ms, two runs) and 1.2x
to 1.3x as long on PlanSys2's corpus (126-143 ms against 101-118 ms).

Why: after the lexer (lexer.py) was made fast, lark's per-token parser step was
the largest cost on big problems, mostly generic bookkeeping (attribute lookups,
action tuples, callback checks on every shift). This driver precompiles lark's
table into plain dicts (shift = next state as an int, reduce = rule size,
callback and goto symbol) and runs the same algorithm in a single loop. Grammar
analysis, the callbacks (our inline builder) and the error classes stay lark's,
so behaviour and error reporting are identical to ``Lark.parse``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from lark import Lark, Token
from lark.exceptions import UnexpectedToken
from lark.parsers.lalr_analysis import Shift

from plansys_bridge.errors import PddlError
from plansys_bridge.pddl.lexer import PddlLexer

Reduce = tuple[int, Callable[[list[Any]], Any], str]


class LalrDriver:
    """Parses with the tables of ``lark`` (built with ``lexer=PddlLexer``)."""

    def __init__(self, lark: Lark) -> None:
        inner = lark.parser.parser.parser
        table = inner.parse_table
        callbacks = inner.callbacks
        self.start_states: dict[str, int] = dict(table.start_states)
        self.end_states: dict[str, int] = dict(table.end_states)
        self.table: dict[int, dict[str, int | Reduce]] = {}
        for state, actions in table.states.items():
            row: dict[str, int | Reduce] = {}
            for symbol, (action, arg) in actions.items():
                if action is Shift:
                    row[symbol] = arg
                else:
                    row[symbol] = (len(arg.expansion), callbacks[arg], arg.origin.name)
            self.table[state] = row
        self.lexer = _pddl_lexer(lark.parser.lexer)

    def parse(self, text: str, start: str) -> Any:
        table = self.table
        stack = [self.start_states[start]]
        values: list[Any] = []
        token: Token | None = None
        for token in self.lexer.tokens(text, table, stack):
            kind = token.type
            while True:
                row = table[stack[-1]]
                act = row.get(kind)
                if act is None:
                    raise UnexpectedToken(token, {t for t in row if t.isupper()})
                if type(act) is int:
                    stack.append(act)
                    values.append(token)
                    break
                size, callback, origin = act  # type: ignore[misc]
                if size:
                    children = values[-size:]
                    del stack[-size:]
                    del values[-size:]
                else:
                    children = []
                values.append(callback(children))
                stack.append(table[stack[-1]][origin])  # type: ignore[arg-type]
        end = (
            Token.new_borrow_pos("$END", "", token)
            if token is not None
            else Token("$END", "", 0, 1, 1)
        )
        end_state = self.end_states[start]
        while True:
            row = table[stack[-1]]
            act = row.get("$END")
            if act is None or isinstance(act, int):
                raise UnexpectedToken(end, {t for t in row if t.isupper()})
            size, callback, origin = act
            if size:
                children = values[-size:]
                del stack[-size:]
                del values[-size:]
            else:
                children = []
            values.append(callback(children))
            stack.append(table[stack[-1]][origin])  # type: ignore[arg-type]
            if stack[-1] == end_state:
                return values[-1]


def _pddl_lexer(lexer: object) -> PddlLexer:
    """Our lexer inside lark's front end.

    Why: lark 1.1 keeps a lexer class of ``__future_interface__ = True`` as it is;
    lark 1.2 and later wrap it in an adapter that holds it as ``.lexer``. Both are
    within the versions the project accepts (lark < 2)."""
    inner = getattr(lexer, "lexer", None)
    for candidate in (lexer, inner):
        if isinstance(candidate, PddlLexer):
            return candidate
    raise PddlError(f"lark built the parser with {type(lexer).__name__}, not PddlLexer")
