"""A mission file's performer entry: the keys every kind shares, checked.

``kind``, ``name``, ``actions`` (``{action: [specialised args]}`` or a list of
names), ``heartbeat_period`` and ``commit_timeout`` are read here; any other key
must be one the kind declares, and is handed to it as a setting. Each mistake is
one ``ConfigError`` naming its key (``performers[2].actions.move[0]``).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any

from plansys_bridge.errors import ConfigError

__all__ = ["COMMON_KEYS", "PerformerConfig", "parse_entry"]


@dataclass(frozen=True)
class PerformerConfig:
    """A mission file's performer entry after the common keys were checked."""

    kind: str
    name: str
    actions: dict[str, tuple[str, ...]]
    heartbeat_period: float
    commit_timeout: float
    settings: dict[str, Any]
    """Kind-specific settings, only keys the class declares in ``settings_keys``."""
    key: str
    """Where the entry is in the mission file, e.g. ``performers[2]``."""


COMMON_KEYS = ("kind", "name", "actions", "heartbeat_period", "commit_timeout")


def parse_entry(
    config: Mapping[str, Any],
    *,
    kind_name: str,
    settings_keys: Collection[str],
    key: str = "performer",
) -> PerformerConfig:
    """Check a mission file's performer entry for a kind (``kind_name`` as users
    read it, ``settings_keys`` its own keys); unknown keys name themselves."""
    if not isinstance(config, Mapping):
        raise ConfigError("a performer entry must be a mapping", key=key)
    allowed = set(COMMON_KEYS) | set(settings_keys)
    for entry_key in config:
        if entry_key not in allowed:
            raise ConfigError(
                f"unknown key for a {kind_name} (allowed: {', '.join(sorted(allowed))})",
                key=f"{key}.{entry_key}",
            )
    kind = config.get("kind", "")
    if not isinstance(kind, str):
        raise ConfigError(f"must be a string, got {kind!r}", key=f"{key}.kind")
    name = config.get("name")
    if not isinstance(name, str) or not name.strip():
        raise ConfigError("a performer needs a non-empty string name", key=f"{key}.name")
    actions = _parse_actions(config.get("actions"), f"{key}.actions")
    heartbeat = _positive(config.get("heartbeat_period", 1.0), f"{key}.heartbeat_period")
    commit = _positive(config.get("commit_timeout", 2.0), f"{key}.commit_timeout")
    settings = {k: v for k, v in config.items() if k not in COMMON_KEYS}
    return PerformerConfig(
        kind=kind,
        name=name.strip(),
        actions=actions,
        heartbeat_period=heartbeat,
        commit_timeout=commit,
        settings=settings,
        key=key,
    )


def _positive(value: object, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ConfigError(f"must be a number > 0, got {value!r}", key=key)
    return float(value)


def _parse_actions(value: object, key: str) -> dict[str, tuple[str, ...]]:
    """``actions`` is ``{action: [specialised args]}`` (or a list of action names)."""
    if value is None:
        raise ConfigError("missing: the actions this performer serves", key=key)
    if isinstance(value, list | tuple):
        value = {name: [] for name in value}
    if not isinstance(value, Mapping) or not value:
        raise ConfigError(
            "must map each action name to its specialised arguments, e.g. {move: [r1]}", key=key
        )
    out: dict[str, tuple[str, ...]] = {}
    for action, args in value.items():
        if not isinstance(action, str) or not action.strip():
            raise ConfigError(f"action names must be strings, got {action!r}", key=key)
        where = f"{key}.{action}"
        if args is None:
            args = []
        if isinstance(args, str) or not isinstance(args, list | tuple):
            raise ConfigError(
                f'specialised arguments must be a list ("" = any), got {args!r}', key=where
            )
        spec: list[str] = []
        for i, arg in enumerate(args):
            text = "" if arg is None else arg
            if not isinstance(text, str):
                raise ConfigError(f"must be a string, got {arg!r}", key=f"{where}[{i}]")
            spec.append(text.strip().lower())
        out[action.strip().lower()] = tuple(spec)
    return out
