"""Loading a mission's ``sensing:`` rules: every name checked before anything starts.

A rule naming an unknown source kind, performer, MAVLink message or field, DBC
signal, topic field, predicate, function or object is a :class:`ConfigError` naming
the mission file with line and column and the key path
(``mission.yaml:14:16:sensing[0].when: no field 'batery_remaining' in BATTERY_STATUS``).
Predicates and functions are checked by the problem expert itself: each rule's
change is tried inside a transaction that is then undone, so the rule is accepted
exactly when the knowledge would accept its writes.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from plansys_bridge.errors import ConfigError, PlansysBridgeError, PluginError
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.plugins import NoSettings, settings_model, validate_settings

from .expressions import Expression, ExpressionError, parse_expression
from .positions import value_position
from .rules import RuleConfig, RuleLogic
from .source import SENSING_SOURCES, RuleSite, SensingSource

__all__ = ["LoadedRule", "load_rules"]


@dataclass(frozen=True)
class LoadedRule:
    """One checked rule, ready to be attached to its source."""

    key: str
    """``sensing[2]``"""
    config: RuleConfig
    source: SensingSource
    when: Expression | None
    clear_when: Expression | None
    value: Expression | None

    def logic(self) -> RuleLogic:
        return RuleLogic(
            predicate=self.config.predicate,
            function=self.config.function,
            when=self.when,
            clear_when=self.clear_when,
            value=self.value,
        )

    def describe(self) -> str:
        who = f"{self.config.performer} " if self.config.performer else ""
        return f"{self.key} ({who}{self.source.describe()})"


class _Rehearsed(Exception):
    """Ends the trial writes so that the transaction undoes them."""


class _Loader:
    def __init__(self, mission: Any, knowledge: ProblemExpert) -> None:
        self.mission = mission
        self.knowledge = knowledge
        self.source_file: str = getattr(mission, "source", "<mission>")
        self.base_dir: Path = getattr(mission, "base_dir", Path("."))

    def error(
        self, message: str, keys: Sequence[str | int], column: int | None = None
    ) -> ConfigError:
        """A ConfigError at ``keys`` (a path below ``sensing``), with line:col when known."""
        path: list[str | int] = ["sensing", *keys]
        key = "sensing" + "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in keys)
        pos = None
        if Path(self.source_file).is_file():
            # a missing key is reported at the rule (or whatever encloses it)
            for end in range(len(path), 0, -1):
                pos = value_position(self.source_file, path[:end])
                if pos is not None:
                    if end < len(path):
                        column = None
                    break
        if pos is None:
            return ConfigError(message, key=key, file=self.source_file)
        col = pos.column
        if column is not None and pos.text_column is not None:
            col = pos.text_column + column - 1
        return ConfigError(message, key=key, file=self.source_file, line=pos.line, column=col)

    @contextmanager
    def keyed(self, keys: Sequence[str | int]) -> Iterator[None]:
        try:
            yield
        except ConfigError as exc:
            # A source's error names its own key (``message``); put it under the rule.
            raise self.error(exc.reason, [*keys, *_key_parts(exc.key)]) from exc
        except PlansysBridgeError as exc:
            raise self.error(str(exc), keys) from exc

    def load(self, index: int, raw: Any) -> LoadedRule:
        if not isinstance(raw, Mapping):
            raise self.error("a rule is a mapping such as {from: mavlink, ...}", [index])
        try:
            config = RuleConfig.model_validate(raw)
        except ValidationError as exc:
            err = exc.errors()[0]
            loc = [str(p) if not isinstance(p, int) else p for p in err["loc"]]
            msg = str(err["msg"]).removeprefix("Value error, ")
            raise self.error(msg, [index, *loc]) from exc
        try:
            cls = SENSING_SOURCES.load(config.source)
        except PluginError as exc:
            raise self.error(str(exc), [index, "from"]) from exc
        entry = self._performer(cls, config, index)
        source = self._source(cls, config, index)
        with self.keyed([index]):
            fields = source.check(RuleSite(entry, self.base_dir, self.mission))
        when = self._expression(config.when, "when", index, fields)
        clear_when = self._expression(config.clear_when, "clear_when", index, fields)
        value = source.value() if config.function is not None else None
        if config.function is not None and value is None:
            raise self.error(
                f"a function rule needs a value: the {config.source} source takes it from "
                f"{' or '.join(sorted(_settings_model(cls).model_fields)) or 'nothing'}",
                [index],
            )
        self._rehearse(config, index)
        return LoadedRule(f"sensing[{index}]", config, source, when, clear_when, value)

    def _source(self, cls: type[SensingSource], config: RuleConfig, index: int) -> SensingSource:
        """The source built from the rule's own keys, validated through its Settings
        model the way every plugin's settings are (plugins.validate_settings)."""
        try:
            settings = validate_settings(
                _settings_model(cls), config.source_settings, known=_COMMON_KEYS
            )
        except ConfigError as exc:
            message = exc.reason
            if message.startswith("unknown key"):
                message = message.replace("unknown key", f"unknown key for a {config.source} rule")
            raise self.error(message, [index, *_key_parts(exc.key)]) from exc
        return cls(settings)

    def _performer(
        self, cls: type[SensingSource], config: RuleConfig, index: int
    ) -> Mapping[str, Any] | None:
        entries = list(getattr(self.mission, "performers", []) or [])
        if config.performer is None:
            if cls.performer_kinds:
                raise self.error(
                    f"a {config.source} rule names the performer whose link it reads",
                    [index, "performer"],
                )
            return None
        found = next((e for e in entries if getattr(e, "name", None) == config.performer), None)
        if found is None:
            names = [str(getattr(e, "name", "")) for e in entries]
            raise self.error(
                f"no performer {config.performer!r}{_did_you_mean(config.performer, names)}",
                [index, "performer"],
            )
        entry = found.model_dump() if hasattr(found, "model_dump") else dict(found)
        if cls.performer_kinds and entry.get("kind") not in cls.performer_kinds:
            raise self.error(
                f"performer {config.performer!r} is of kind {entry.get('kind')!r}; a "
                f"{config.source} rule reads a {' or '.join(cls.performer_kinds)} performer",
                [index, "performer"],
            )
        return dict(entry)

    def _expression(
        self, text: str | None, key: str, index: int, fields: frozenset[str] | None
    ) -> Expression | None:
        if text is None:
            return None
        try:
            expr = parse_expression(text)
        except ExpressionError as exc:
            raise self.error(exc.message, [index, key], exc.column) from exc
        if fields is not None:
            for name in sorted(n for n in expr.fields if n not in fields):
                column = text.find(name) + 1 or None
                raise self.error(
                    f"no field {name!r} in what this rule reads"
                    f"{_did_you_mean(name, sorted(fields))}",
                    [index, key],
                    column,
                )
        return expr

    def _rehearse(self, config: RuleConfig, index: int) -> None:
        """Try the rule's writes on the knowledge and undo them."""
        key = "predicate" if config.predicate is not None else "function"
        target = config.predicate if config.predicate is not None else config.function
        assert target is not None
        text = target.strip()
        if not (text.startswith("(") and text.endswith(")")) or "=" in text:
            raise self.error(f"expected a ground {key} such as (battery_low uav1)", [index, key])
        try:
            with self.keyed([index, key]), self.knowledge.transaction():
                if config.predicate is not None:
                    self.knowledge.add_predicate(text)
                    self.knowledge.remove_predicate(text)
                else:
                    self.knowledge.set_function(f"(= {text} 0)")
                raise _Rehearsed
        except _Rehearsed:
            pass


def _key_parts(key: str | None) -> list[str | int]:
    """``bus.ids[2]`` -> ``["bus", "ids", 2]`` (a key path back into YAML keys)."""
    parts = re.findall(r"[^.\[\]]+|\[\d+\]", key or "")
    return [int(p[1:-1]) if p.startswith("[") else p for p in parts]


def _settings_model(cls: type[SensingSource]) -> type[BaseModel]:
    return settings_model(cls) or NoSettings


_COMMON_KEYS = ("from", "performer", "when", "clear_when", "predicate", "function", "every")


def _did_you_mean(name: str, known: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, list(known), n=1)
    if close:
        return f" (did you mean {close[0]!r}?)"
    return f" (known: {', '.join(known[:12])}{', ...' if len(known) > 12 else ''})" if known else ""


def load_rules(mission: Any, knowledge: ProblemExpert) -> list[LoadedRule]:
    """Check every rule of ``mission.sensing`` against the sources, the performers
    and the knowledge; the first bad one is a ConfigError naming its place."""
    loader = _Loader(mission, knowledge)
    return [loader.load(i, raw) for i, raw in enumerate(getattr(mission, "sensing", []) or [])]
