"""PDDL text -> model: lark LALR parse, then semantic checks.

Why this shape: one cached LALR parser with a contextual lexer and an inline
transformer (:mod:`plansys_bridge.pddl.builder`) builds the model in a single pass
with no intermediate tree, which is what makes large problems fast. The text is
lower-cased before lexing (PDDL is case-insensitive and has no string literals);
error snippets quote the original text. Trailing text after the definition's
closing parenthesis is ignored, as PlanSys2 does.
"""

from __future__ import annotations

import re
import threading
from collections.abc import Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

from lark import Lark
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken
from lark.lexer import PatternStr

from plansys_bridge.errors import PddlError, PddlSyntaxError, SourceLocation
from plansys_bridge.pddl import checks
from plansys_bridge.pddl.builder import Builder
from plansys_bridge.pddl.diagnostics import location_at, snippet, with_snippet
from plansys_bridge.pddl.driver import LalrDriver
from plansys_bridge.pddl.lexer import PddlLexer
from plansys_bridge.pddl.merge import merge_domains
from plansys_bridge.pddl.model import (
    Atom,
    Condition,
    Domain,
    Effect,
    FluentValue,
    Problem,
    is_variable,
)
from plansys_bridge.textfile import TextFileError, read_text

__all__ = [
    "parse_atom",
    "parse_condition",
    "parse_domain",
    "parse_domain_files",
    "parse_effect",
    "parse_fluent_value",
    "parse_problem",
]

_STARTS = (
    "domain",
    "problem",
    "condition_entry",
    "effect_entry",
    "atom_entry",
    "fluent_value_entry",
)

_TERMINAL_WORDS = {
    "NAME": "a name",
    "VARIABLE": "a variable",
    "TERM": "a name or a variable",
    "NUMBER": "a number",
    "REQUIREMENT": "a requirement such as :typing",
    "TIME_SPEC": "'at start', 'over all' or 'at end'",
    "ARITH": "an arithmetic operator",
    "COMP": "a comparison (=, <, <=, >, >=)",
    "$END": "the end of the text",
}

_lock = threading.Lock()
_builder = Builder()
_lark: Lark | None = None
_driver: LalrDriver | None = None
_terminal_text: dict[str, str] = {}


def _parser() -> Lark:
    """The shared parser, built on first use."""
    global _lark
    if _lark is None:
        grammar = resources.files(__package__).joinpath("grammar.lark").read_text("utf-8")
        lark = Lark(
            grammar,
            parser="lalr",
            lexer=PddlLexer,
            start=list(_STARTS),
            transformer=_builder,
            maybe_placeholders=False,
        )
        for term in lark.terminals:
            if isinstance(term.pattern, PatternStr):
                _terminal_text[term.name] = repr(term.pattern.value)
        _lark = lark
    return _lark


def _get_driver() -> LalrDriver:
    global _driver
    if _driver is None:
        _driver = LalrDriver(_parser())
    return _driver


def _lower(text: str) -> str:
    """Lower-case without moving any character (keeps line/column exact)."""
    lowered = text.lower()
    if len(lowered) == len(text):
        return lowered
    return "".join(ch if len(ch.lower()) != 1 else ch.lower() for ch in text)


_PARENS = re.compile(r";[^\n]*|[()]")


def _definition_end(text: str) -> int | None:
    """Offset just after the parenthesis closing the first top-level form."""
    depth = 0
    for match in _PARENS.finditer(text):
        tok = match.group()
        if tok == "(":
            depth += 1
        elif tok == ")":
            depth -= 1
            if depth == 0:
                return match.end()
    return None


def _describe(expected: Sequence[str] | set[str]) -> str:
    words = sorted(
        {_terminal_text.get(name) or _TERMINAL_WORDS.get(name, name) for name in expected}
    )
    if not words:
        return ""
    if len(words) > 8:
        words = [*words[:8], "..."]
    return ", expected " + (
        words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]
    )


def _syntax_error(exc: UnexpectedInput, text: str, filename: str) -> PddlSyntaxError:
    if isinstance(exc, UnexpectedEOF):
        end = len(text.rstrip())
        loc = location_at(text, end, filename)
        message = "unexpected end of text (unbalanced parentheses?)" + _describe(exc.expected)
    elif isinstance(exc, UnexpectedToken):
        tok = exc.token
        if tok.type == "$END":
            loc = location_at(text, len(text.rstrip()), filename)
            message = "unexpected end of text (unbalanced parentheses?)"
        else:
            loc = SourceLocation(filename, tok.line or 1, tok.column or 1)
            start = tok.start_pos or 0
            shown = text[start : tok.end_pos] if tok.end_pos is not None else str(tok)
            message = f"unexpected {shown!r}"
        message += _describe(exc.expected)
    else:
        assert isinstance(exc, UnexpectedCharacters)
        loc = SourceLocation(filename, exc.line, exc.column)
        message = f"unexpected character {text[exc.pos_in_stream or 0]!r}" + _describe(
            exc.allowed or ()
        )
    return PddlSyntaxError(message, loc, snippet(text, loc.line, loc.column))


def _error_offset(exc: UnexpectedInput) -> int | None:
    if isinstance(exc, UnexpectedToken):
        return exc.token.start_pos
    if isinstance(exc, UnexpectedCharacters):
        return exc.pos_in_stream
    return None


def _parse(text: str, start: str, filename: str) -> Any:
    """Run the LALR parser; lark errors become PddlSyntaxError with a snippet."""
    lowered = _lower(text)
    with _lock:
        parser = _get_driver()
        _builder.file = filename
        try:
            try:
                return parser.parse(lowered, start=start)
            except UnexpectedInput as exc:
                end = _definition_end(lowered) if start in ("domain", "problem") else None
                offset = _error_offset(exc)
                if end is None or offset is None or offset < end:
                    raise
                return parser.parse(lowered[:end], start=start)
        except UnexpectedInput as exc:
            raise _syntax_error(exc, text, filename) from exc
        except PddlError as exc:
            if exc.snippet is None and exc.location is not None:
                raise with_snippet(type(exc), exc.message, exc.location, {filename: text}) from exc
            raise


# ---------------------------------------------------------------- public API


def parse_domain(text: str, filename: str = "<domain>", *, check: bool = True) -> Domain:
    """Parse one domain text; with ``check`` (default) also validate it."""
    domain = merge_domains([_parse(text, "domain", filename)], {filename: text})
    if check:
        checks.check_domain(domain, {filename: text})
    return domain


def parse_domain_files(paths: Sequence[str | Path]) -> Domain:
    """Parse several domain files and merge them into one (PlanSys2's a.pddl:b.pddl).

    Each file is parsed on its own, then merged; the checks run on the merged
    domain so one file may use types declared in another.
    """
    if not paths:
        raise PddlSyntaxError("no domain files given")
    sources: dict[str, str] = {}
    domains: list[Domain] = []
    for path in paths:
        name = str(path)
        try:
            text = read_text(path, "domain file")
        except TextFileError as exc:
            location = exc.location or SourceLocation(name, 1, 1)
            raise PddlSyntaxError(exc.reason, location) from exc
        sources[name] = text
        domains.append(_parse(text, "domain", name))
    merged = merge_domains(domains, sources)
    checks.check_domain(merged, sources)
    return merged


def parse_problem(
    text: str,
    domain: Domain | None = None,
    filename: str = "<problem>",
) -> Problem:
    """Parse a problem; with a domain, check it against that domain."""
    problem: Problem = _parse(text, "problem", filename)
    sources = {filename: text}
    checks.check_problem(problem, domain, sources)
    return problem


def parse_condition(
    text: str,
    domain: Domain | None = None,
    variables: Mapping[str, tuple[str, ...]] | None = None,
    filename: str = "<condition>",
    *,
    objects: Mapping[str, str] | None = None,
) -> Condition:
    """Parse a condition such as a goal ``(and (dish_prepared d1))``.

    ``variables`` maps free variables (``"?r"``) to their types; any other free
    variable is an error. ``objects`` (name -> type), when given, makes unknown
    object names an error and type-checks them; without it only the domain's
    constants are checked.
    """
    cond: Condition = _parse(text, "condition_entry", filename)
    if domain is not None:
        checks.check_condition(cond, domain, variables or {}, {filename: text}, objects)
    return cond


def parse_effect(
    text: str,
    domain: Domain | None = None,
    variables: Mapping[str, tuple[str, ...]] | None = None,
    filename: str = "<effect>",
    *,
    objects: Mapping[str, str] | None = None,
) -> Effect:
    """Parse an effect such as ``(and (robot_at r1 kitchen) (not (robot_at r1 hall)))``."""
    eff: Effect = _parse(text, "effect_entry", filename)
    if domain is not None:
        checks.check_effect(eff, domain, variables or {}, {filename: text}, objects)
    return eff


def parse_atom(
    text: str,
    domain: Domain | None = None,
    filename: str = "<atom>",
    *,
    objects: Mapping[str, str] | None = None,
) -> Atom:
    """Parse a ground fact such as ``(robot_at r1 kitchen)``."""
    atom: Atom = _parse(text, "atom_entry", filename)
    sources = {filename: text}
    for index, arg in enumerate(atom.args):
        if is_variable(arg):
            raise checks.arg_error(
                f"a fact must be ground, found variable {arg}", atom, index, sources
            )
    if domain is not None:
        checks.check_condition(atom, domain, {}, sources, objects)
    return atom


def parse_fluent_value(
    text: str,
    domain: Domain | None = None,
    filename: str = "<fluent>",
    *,
    objects: Mapping[str, str] | None = None,
) -> FluentValue:
    """Parse a numeric fact such as ``(= (battery r1) 80)``."""
    value: FluentValue = _parse(text, "fluent_value_entry", filename)
    sources = {filename: text}
    for index, arg in enumerate(value.fluent.args):
        if is_variable(arg):
            raise checks.arg_error(
                f"a fluent value must be ground, found variable {arg}", value.fluent, index, sources
            )
    if domain is not None:
        checks.check_fluent_value(value, domain, sources, objects)
    return value
