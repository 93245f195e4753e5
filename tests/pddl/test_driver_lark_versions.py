"""The parser's hold on its lexer across the lark versions the project accepts.

lark 1.1 keeps a custom lexer class as it is; lark 1.2 and later wrap it in an
adapter holding it as ``.lexer`` and hand ``lex()`` a TextSlice instead of a str.
The suite runs on one lark (the ``pddl`` peer pins lark < 1.2); these tests make
the other's shapes with lark's own classes where the installed lark has them."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from lark.lexer import Lexer

from plansys_bridge.errors import PddlError
from plansys_bridge.pddl import parser
from plansys_bridge.pddl.driver import _pddl_lexer
from plansys_bridge.pddl.lexer import PddlLexer


def _our_lexer() -> PddlLexer:
    lexer = parser._get_driver().lexer
    assert isinstance(lexer, PddlLexer)
    return lexer


class _Wrapper(Lexer):
    """The shape of lark 1.2+'s adapter for a lexer of interface 1."""

    def __init__(self, inner: object) -> None:
        self.lexer = inner

    def lex(self, lexer_state, parser_state):  # type: ignore[no-untyped-def]
        return self.lexer.lex(lexer_state, parser_state)  # type: ignore[attr-defined]


def test_plain_lexer_is_taken_as_it_is() -> None:
    ours = _our_lexer()
    assert _pddl_lexer(ours) is ours


def test_wrapped_lexer_is_unwrapped() -> None:
    ours = _our_lexer()
    assert _pddl_lexer(_Wrapper(ours)) is ours


def test_foreign_lexer_is_a_clear_error() -> None:
    with pytest.raises(PddlError, match="not PddlLexer"):
        _pddl_lexer(_Wrapper(object()))


def test_lex_takes_a_text_slice_as_the_str() -> None:
    """lex() gives the same tokens for the text and for a whole-text slice of it."""
    lark = parser._parser()
    text = "(define (domain d) (:predicates (p ?x)))"
    ours = _our_lexer()

    def tokens(given: object) -> list[tuple[str, str]]:
        state = SimpleNamespace(text=given)
        parser_state = SimpleNamespace(
            parse_conf=SimpleNamespace(states=lark.parser.parser.parser.parse_table.states),
            state_stack=[lark.parser.parser.parser.parse_table.start_states["domain"]],
        )
        out = []
        for token in ours.lex(state, parser_state):  # type: ignore[arg-type]
            out.append((token.type, str(token)))
            if len(out) == 3:
                break
        return out

    try:
        from lark.utils import TextSlice  # type: ignore[attr-defined]
    except ImportError:  # lark 1.1: a slice of our own shape
        whole: object = SimpleNamespace(text=text, start=0, end=len(text))
    else:
        whole = TextSlice(text, 0, len(text))
    assert tokens(whole) == tokens(text)
    assert tokens(text)[0] == ("LPAR", "(")
