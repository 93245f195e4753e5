"""Compiler-style error reporting for PDDL texts: ``file:line:col`` plus a caret.

A robotics engineer reading a log at the robot needs to see the offending line,
not just its number, so every PDDL error carries a snippet built here. Locations
only store file/line/column; the texts are looked up when an error is raised,
which keeps the happy path free of per-node bookkeeping.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from plansys_bridge.errors import PddlError, PddlSemanticError, SourceLocation

_TOKEN = re.compile(r"\s+|;[^\n]*|[()]|[^\s()]+")


SNIPPET_WIDTH = 200
"""Longest part of a source line a snippet quotes."""


def snippet(text: str, line: int, column: int) -> str | None:
    """Quote ``line`` of ``text`` with a caret under ``column`` (both 1-based)."""
    lines = text.splitlines()
    if not 1 <= line <= len(lines):
        return None
    source = lines[line - 1].rstrip()
    column = max(column, 1)
    if len(source) > SNIPPET_WIDTH:  # a generated one-line file: quote around the column
        start = max(0, min(column - 1 - SNIPPET_WIDTH // 2, len(source) - SNIPPET_WIDTH))
        end = start + SNIPPET_WIDTH
        head = "..." if start > 0 else ""
        source = head + source[start:end] + ("..." if end < len(source) else "")
        column = column - start + len(head)
    prefix = "".join(c if c == "\t" else " " for c in source[: column - 1])
    gutter = f"{line:>5} | "
    return f"{gutter}{source}\n{' ' * (len(gutter) - 2)}| {prefix}^"


def offset_of(text: str, line: int, column: int) -> int:
    """Character offset of a 1-based line/column in ``text``."""
    offset = 0
    for _ in range(line - 1):
        nl = text.find("\n", offset)
        if nl < 0:
            return len(text)
        offset = nl + 1
    return offset + column - 1


def location_at(text: str, offset: int, file: str) -> SourceLocation:
    """The 1-based location of a character offset."""
    line = text.count("\n", 0, offset) + 1
    start = text.rfind("\n", 0, offset) + 1
    return SourceLocation(file, line, offset - start + 1)


def nth_token_after(sources: Mapping[str, str], loc: SourceLocation, index: int) -> SourceLocation:
    """Location of the ``index``-th token after the token at ``loc`` (1 = next).

    Used to point at the offending argument of an atom whose location is its
    predicate name; falls back to ``loc`` when the text is not available or does
    not have that many tokens before the atom closes.
    """
    text = sources.get(loc.file)
    if text is None or index <= 0:
        return loc
    pos = offset_of(text, loc.line, loc.column)
    count = -1
    for match in _TOKEN.finditer(text, pos):
        tok = match.group()
        if tok[0].isspace() or tok[0] == ";":
            continue
        if tok in "()":
            return loc
        count += 1
        if count == index:
            return location_at(text, match.start(), loc.file)
    return loc


def with_snippet(
    cls: type[PddlError],
    message: str,
    loc: SourceLocation | None,
    sources: Mapping[str, str],
) -> PddlError:
    """Build an error of class ``cls`` at ``loc`` quoting the source when known."""
    snip = None
    if loc is not None and loc.file in sources:
        snip = snippet(sources[loc.file], loc.line, loc.column)
    return cls(message, loc, snip)


def semantic_error(
    message: str, loc: SourceLocation | None, sources: Mapping[str, str]
) -> PddlSemanticError:
    err = with_snippet(PddlSemanticError, message, loc, sources)
    assert isinstance(err, PddlSemanticError)
    return err
