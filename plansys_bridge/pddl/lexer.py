"""A contextual PDDL lexer for lark's LALR parser, written for speed.

Kept because ``benchmarks/bench_parse.py`` shows what it is worth. Under lark's
own parse loop, swapping this lexer for lark's contextual one makes the whole
parse 1.9x to 2.6x as slow on a generated problem of 5000 objects (822-828 ms
against 320-443 ms, two runs) and 1.5x to 1.8x on PlanSys2's corpus (214-224 ms
against 126-143 ms for its 66 files); with the driver (driver.py) as well, ours
takes 293-296 ms and 101-118 ms.

Why not lark's own contextual lexer: on large problems (thousands of facts) the
parse time was dominated by lexing, one regex match per token *plus* one per
whitespace run, each going through several layers of generic lark code. PDDL's
tokens are simple, so one precompiled regex that skips whitespace and comments
and captures the next token does the job in a single match.

It is still contextual, as lark's is: a word is a keyword (``and``, ``either``,
``at start``, ``:domain``...) only where the parser can accept that keyword,
otherwise a name; inside an atom's argument list, names and variables are both
``TERM`` so the grammar can spell atoms without a reduction per argument. The
parser's current state is read from ``parser_state`` when each token is made.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from typing import Any

from lark import Token
from lark.exceptions import UnexpectedCharacters
from lark.lexer import Lexer, LexerState, PatternStr

_TOKEN = re.compile(
    r"(?:\s++|;[^\n]*+)*+"
    r"(?:(?P<LPAR>\()|(?P<RPAR>\))"
    r"|(?P<word>[a-z][a-z0-9_\-]*)"
    r"|(?P<var>\?[a-z][a-z0-9_\-]*)"
    r"|(?P<colon>:[a-z][a-z0-9_\-]*)"
    r"|(?P<NUMBER>[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:e[+-]?\d+)?(?![a-z0-9_\-]))"
    r"|(?P<COMP><=|>=|<|>|=)|(?P<MINUS>-)|(?P<ARITH>[+*/]))"
)
_SKIP = re.compile(r"(?:\s++|;[^\n]*+)*+")
_TIME_SPEC = re.compile(r"(?:at\s+(?:start|end)|over\s+all)(?![a-z0-9_\-])")


def _token(new: Any, kind: str, value: str, start: int, line: int, column: int, end: int) -> Token:
    tok: Token = new(Token, value)
    tok.type = kind
    tok.value = value
    tok.start_pos = start
    tok.line = tok.end_line = line
    tok.column = column
    tok.end_column = column + end - start
    tok.end_pos = end
    return tok


class PddlLexer(Lexer):
    """Plugged into ``Lark(lexer=PddlLexer)``; see the module docstring."""

    __future_interface__ = True

    def __init__(self, lexer_conf: Any) -> None:
        self.keywords: dict[str, str] = {}
        for term in lexer_conf.terminals:
            if isinstance(term.pattern, PatternStr):
                self.keywords[term.pattern.value] = term.name
        # The token regex names its groups after lark's terminals for these.
        assert self.keywords["("] == "LPAR" and self.keywords[")"] == "RPAR"
        assert self.keywords["-"] == "MINUS"

    def lex(self, lexer_state: LexerState, parser_state: Any) -> Iterator[Token]:
        # lark 1.2 and later hand over a TextSlice (whole text, as checked by lark's
        # adapter for this interface) where lark 1.1 hands over the str.
        text = lexer_state.text
        if not isinstance(text, str):
            text = text.text
        return self.tokens(text, parser_state.parse_conf.states, parser_state.state_stack)

    def tokens(
        self, text: str, states: Mapping[int, Mapping[str, Any]], stack: list[int]
    ) -> Iterator[Token]:
        """Tokens of ``text``; ``states[stack[-1]]`` holds what the parser accepts now."""
        keywords = self.keywords
        match = _TOKEN.match
        new = str.__new__
        pos = 0
        line = 1
        line_start = 0
        end = len(text)
        while pos < end:
            m = match(text, pos)
            if m is None:
                skipped = _SKIP.match(text, pos)
                start = skipped.end() if skipped else pos
                line += text.count("\n", pos, start)
                line_start = text.rfind("\n", 0, start) + 1
                if start >= end:
                    return
                raise UnexpectedCharacters(
                    text,
                    start,
                    line,
                    start - line_start + 1,
                    allowed={t for t in states[stack[-1]] if t.isupper()},
                )
            kind = m.lastgroup
            assert kind is not None
            start = m.start(kind)
            if start != pos:
                newlines = text.count("\n", pos, start)
                if newlines:
                    line += newlines
                    line_start = text.rfind("\n", pos, start) + 1
            value = m.group(kind)
            pos = m.end()
            if kind == "word":
                accepts = states[stack[-1]]
                keyword = keywords.get(value)
                if keyword is not None and keyword in accepts:
                    kind = keyword
                elif "TIME_SPEC" in accepts and (timed := _TIME_SPEC.match(text, start)):
                    kind = "TIME_SPEC"
                    value = timed.group()
                    pos = timed.end()
                    if "\n" in value:  # "at\n start": keep later lines right
                        tok = _token(new, kind, value, start, line, start - line_start + 1, pos)
                        line += value.count("\n")
                        line_start = text.rfind("\n", start, pos) + 1
                        yield tok
                        continue
                elif "TERM" in accepts:
                    kind = "TERM"
                elif "NAME" in accepts or keyword is None:
                    kind = "NAME"
                else:
                    kind = keyword
            elif kind == "var":
                kind = "TERM" if "TERM" in states[stack[-1]] else "VARIABLE"
            elif kind == "colon":
                keyword = keywords.get(value)
                if keyword is None or (
                    keyword not in states[stack[-1]] and "REQUIREMENT" in states[stack[-1]]
                ):
                    kind = "REQUIREMENT"
                else:
                    kind = keyword
            tok = new(Token, value)
            tok.type = kind
            tok.value = value
            tok.start_pos = start
            tok.line = tok.end_line = line
            tok.column = start - line_start + 1
            tok.end_column = pos - line_start + 1
            tok.end_pos = pos
            yield tok
