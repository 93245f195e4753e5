"""Where a key of a YAML file is: line and column, for load errors a user can jump to.

Mission files are read into plain dicts, which forget positions; a load error about
a sensing rule should still say ``mission.yaml:14:16`` like a compiler. The file is
composed again (PyYAML keeps marks on nodes) and the key path walked to the value.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import yaml


@dataclass(frozen=True)
class ValuePosition:
    """A value's place: 1-based line and column, and where its text starts."""

    line: int
    column: int
    text_column: int | None
    """Column of the first character of a one-line scalar's text (after a quote),
    None for block scalars and containers (their inner columns are not the text's)."""


def value_position(path: str | Path, keys: Sequence[str | int]) -> ValuePosition | None:
    """The position of the value at ``keys`` in the YAML file, None when unknown."""
    try:
        node = yaml.compose(Path(path).read_text("utf-8"), Loader=yaml.SafeLoader)
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
    for key in keys:
        if isinstance(node, yaml.MappingNode) and isinstance(key, str):
            node = next((v for k, v in node.value if getattr(k, "value", None) == key), None)
        elif isinstance(node, yaml.SequenceNode) and isinstance(key, int):
            node = node.value[key] if 0 <= key < len(node.value) else None
        else:
            return None
        if node is None:
            return None
    if node is None:
        return None
    mark = node.start_mark
    text_column = None
    if isinstance(node, yaml.ScalarNode) and node.start_mark.line == node.end_mark.line:
        quoted = node.style in ("'", '"')
        text_column = mark.column + 1 + (1 if quoted else 0)
    return ValuePosition(mark.line + 1, mark.column + 1, text_column)
