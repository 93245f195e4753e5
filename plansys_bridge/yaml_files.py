"""YAML files a user writes (missions, locations, segments), read strictly.

Repeated keys are errors (YAML would keep the last silently), nesting deeper than a
settings file needs is refused before PyYAML's recursive composer overflows, and the
position of every key is kept so a validation error found later can name the line
and column it is about.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from plansys_bridge.errors import ConfigError
from plansys_bridge.plugins import join_key, key_path
from plansys_bridge.textfile import TextFileError, read_text

__all__ = ["MAX_YAML_DEPTH", "KeyPositions", "load_yaml_document", "load_yaml_file"]


class _UniqueKeyLoader(yaml.SafeLoader):
    """YAML keeps the last of two equal keys; in a mission file the first is then a
    setting silently ignored (two ``performers:`` lists, two ``goal:``), so it is an error."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[Any] = set()
        for key_node, _value in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue  # ``<<: *anchor``: its keys may be overridden
            key = self.construct_object(key_node, deep=deep)
            if not isinstance(key, str | int | float | bool):
                continue  # an unhashable key: the base class reports it
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark
                )
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


MAX_YAML_DEPTH = 100
"""Deeper nesting is refused before PyYAML builds it (its recursive composer would
end in a RecursionError; no settings file needs more than a handful of levels)."""


def _check_depth(text: str, path: Path, key: str | None) -> None:
    """Walk the YAML events (PyYAML's parser is not recursive) and refuse nesting
    deeper than MAX_YAML_DEPTH, naming the place and the key path that leads there."""
    # each open container: [is_mapping, next_is_key, current key/index]
    stack: list[list[Any]] = []
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.CollectionEndEvent):
            stack.pop()
            _advance(stack)
            continue
        if not isinstance(event, yaml.NodeEvent):
            continue
        top = stack[-1] if stack else None
        if top is not None and top[0] and top[1]:  # a mapping key
            value = getattr(event, "value", None)
            top[2] = value if isinstance(value, str) else "?"
            top[1] = False
            if isinstance(event, yaml.CollectionStartEvent):
                stack.append([isinstance(event, yaml.MappingStartEvent), True, 0])
            continue
        if isinstance(event, yaml.CollectionStartEvent):
            if len(stack) >= MAX_YAML_DEPTH:
                mark = event.start_mark
                where = key_path(tuple(level[2] for level in stack[:4])) + "..."
                raise ConfigError(
                    f"nested more than {MAX_YAML_DEPTH} levels deep",
                    key=f"{key}: {where}" if key else where,
                    file=str(path),
                    line=mark.line + 1 if mark else None,
                    column=mark.column + 1 if mark else None,
                )
            stack.append([isinstance(event, yaml.MappingStartEvent), True, 0])
            continue
        _advance(stack)


def _advance(stack: list[list[Any]]) -> None:
    """A value was completed in the innermost container: expect the next key or item."""
    if not stack:
        return
    top = stack[-1]
    if top[0]:
        top[1] = True
    else:
        top[2] += 1


def load_yaml_file(path: str | Path, what: str = "file", key: str | None = None) -> Any:
    """Read a YAML file a user names (mission, locations, segments, ...).

    Unreadable or binary files, YAML syntax errors and repeated keys become one
    ConfigError naming the file (with line:col where YAML knows it) and ``key``,
    the mission key that named the file.
    """
    return load_yaml_document(path, what, key)[0]


def load_yaml_document(
    path: str | Path, what: str = "file", key: str | None = None
) -> tuple[Any, KeyPositions]:
    """Like :func:`load_yaml_file`, with where each key and list item is in the file."""
    p = Path(path)
    try:
        text = read_text(p, what)
    except TextFileError as exc:
        raise ConfigError(exc.reason, key=key, file=str(exc.location or p)) from exc
    try:
        _check_depth(text, p, key)
        loader = _UniqueKeyLoader(text)
        try:
            node = loader.get_single_node()
            data = loader.construct_document(node) if node is not None else None
        finally:
            loader.dispose()
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{p}:{mark.line + 1}:{mark.column + 1}" if mark is not None else str(p)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"not valid YAML: {problem}", key=key, file=where) from exc
    return data, KeyPositions.of(node, str(p))


class KeyPositions:
    """Where each key path (``performers[1].bus.interface``) starts in a YAML file, so
    that an error found while validating the data can name the line and column."""

    def __init__(self, file: str, marks: dict[str, tuple[int, int]] | None = None) -> None:
        self.file = file
        self.marks: dict[str, tuple[int, int]] = marks or {}

    @classmethod
    def of(cls, node: yaml.Node | None, file: str) -> KeyPositions:
        marks: dict[str, tuple[int, int]] = {}
        stack: list[tuple[yaml.Node, str]] = [(node, "")] if node is not None else []
        seen: set[int] = set()
        while stack:
            item, path = stack.pop()
            if id(item) in seen:  # an alias of an anchor already walked
                continue
            seen.add(id(item))
            if isinstance(item, yaml.MappingNode):
                for key_node, value in item.value:
                    if key_node.tag == "tag:yaml.org,2002:merge":
                        stack.append((value, path))
                        continue
                    name = key_node.value if isinstance(key_node, yaml.ScalarNode) else "?"
                    sub = join_key(path, str(name))
                    marks.setdefault(
                        sub, (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
                    )
                    stack.append((value, sub))
            elif isinstance(item, yaml.SequenceNode):
                for i, value in enumerate(item.value):
                    sub = f"{path}[{i}]"
                    marks.setdefault(sub, (value.start_mark.line + 1, value.start_mark.column + 1))
                    stack.append((value, sub))
        return cls(file, marks)

    def locate(self, key: str | None) -> tuple[int, int] | None:
        """Line and column of ``key``, or of the nearest enclosing key the file has
        (a missing key is reported where its mapping is)."""
        while key:
            found = self.marks.get(key)
            if found is not None:
                return found
            cut = max(key.rfind("."), key.rfind("["))
            key = key[:cut] if cut > 0 else ""
        return None

    def relocate(self, exc: ConfigError) -> ConfigError:
        """``exc`` with this file, line and column added; unchanged when it already
        names a place or is about another file (a locations file, say)."""
        if exc.line is not None or exc.file not in (None, self.file):
            return exc
        line, column = self.locate(exc.key) or (None, None)
        return ConfigError(exc.reason, key=exc.key, file=self.file, line=line, column=column)
