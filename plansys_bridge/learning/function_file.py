"""Read a functions file (``learn --functions`` writes one) into the knowledge.

The file holds problem init entries, one ``(= (f a b) 4.2)`` after the other, with
``;`` comments. Each entry goes through the problem expert like any other function
value (so an unknown function or object is refused), and an error names
``file:line:col`` of the entry.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Protocol

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.textfile import TextFileError, read_text

__all__ = ["function_entries", "load_function_file"]


class EntrySyntaxError(ValueError):
    def __init__(self, line: int, column: int, message: str) -> None:
        self.line, self.column = line, column
        super().__init__(message)


class _Knowledge(Protocol):
    def set_function(self, value: str) -> object: ...


def function_entries(text: str) -> Iterator[tuple[int, int, str]]:
    """(line, column, entry text) of each top-level parenthesised form."""
    depth = 0
    start = (0, 0, 0)
    line, col = 1, 0
    in_comment = False
    for i, ch in enumerate(text):
        col += 1
        if ch == "\n":
            line, col, in_comment = line + 1, 0, False
            continue
        if in_comment:
            continue
        if ch == ";":
            in_comment = True
        elif ch == "(":
            if depth == 0:
                start = (line, col, i)
            depth += 1
        elif ch == ")":
            depth -= 1
            if depth < 0:
                raise EntrySyntaxError(line, col, "a ')' without its '('")
            if depth == 0:
                yield start[0], start[1], text[start[2] : i + 1]
        elif depth == 0 and not ch.isspace():
            raise EntrySyntaxError(line, col, "expected '(' of an entry like (= (f a) 1.5)")
    if depth:
        raise EntrySyntaxError(start[0], start[1], "this '(' is never closed")


def load_function_file(knowledge: _Knowledge, path: Path, key: str) -> int:
    """Set every function value of the file; returns how many."""
    try:
        text = read_text(path, "functions file")
    except TextFileError as exc:
        raise ConfigError(exc.reason, key=key, file=str(exc.location or path)) from exc
    count = 0
    try:
        for line, col, entry in function_entries(text):
            try:
                knowledge.set_function(entry)
            except PlansysBridgeError as exc:
                raise ConfigError(str(exc), key=key, file=f"{path}:{line}:{col}") from exc
            count += 1
    except EntrySyntaxError as exc:
        raise ConfigError(str(exc), key=key, file=f"{path}:{exc.line}:{exc.column}") from exc
    return count
