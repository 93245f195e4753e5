"""A mission file's performer entry: the keys every kind shares and the kind's settings.

Every performer entry has the common keys (``kind``, ``name``, ``actions``,
``heartbeat_period``, ``commit_timeout``); the rest belongs to the kind and is
validated through the pydantic ``Settings`` model its class declares
(:mod:`plansys_bridge.plugins`). A kind written before that shape lists its keys in
``settings_keys`` and checks them in ``__init__``; both keep working.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.plugins import NoSettings, settings_model, validate_settings

if TYPE_CHECKING:
    from plansys_bridge.performers.goal import PerformerContext

__all__ = ["COMMON_KEYS", "PerformerConfig", "construct", "has_settings_model", "parse_entry"]

COMMON_KEYS = ("kind", "name", "actions", "heartbeat_period", "commit_timeout")


@dataclass(frozen=True)
class PerformerConfig:
    """A mission file's performer entry after the common keys were checked."""

    kind: str
    name: str
    actions: dict[str, tuple[str, ...]]
    heartbeat_period: float
    commit_timeout: float
    settings: Any
    """The kind's settings: its validated ``Settings`` instance (or what the kind's
    ``prepare`` made of it); for a kind without ``Settings``, the ``settings_keys``
    given, as a dict."""
    key: str
    """Where the entry is in the mission file, e.g. ``performers[2]``."""
    raw: Mapping[str, Any]
    """The entry as written."""


def has_settings_model(cls: type) -> bool:
    """Does the performer class declare its settings as a pydantic ``Settings`` model?"""
    model = settings_model(cls)
    return model is not None and model is not NoSettings


def parse_entry(cls: Any, config: Mapping[str, Any], *, key: str = "performer") -> PerformerConfig:
    """Check the common keys and the kind's settings; every error names its key."""
    if not isinstance(config, Mapping):
        raise ConfigError("a performer entry must be a mapping", key=key)
    kind = config.get("kind", "")
    if not isinstance(kind, str):
        raise ConfigError(f"must be a string, got {kind!r}", key=f"{key}.kind")
    name = config.get("name")
    if not isinstance(name, str) or not name.strip():
        raise ConfigError("a performer needs a non-empty string name", key=f"{key}.name")
    rest = {k: v for k, v in config.items() if k not in COMMON_KEYS}
    settings: Any
    if has_settings_model(cls):
        settings = validate_settings(cls.Settings, rest, key=key, known=COMMON_KEYS)
    else:
        allowed = set(COMMON_KEYS) | set(cls.settings_keys)
        for entry_key in config:
            if entry_key not in allowed:
                raise ConfigError(
                    f"unknown key for a {cls.__name__} (allowed: {', '.join(sorted(allowed))})",
                    key=f"{key}.{entry_key}",
                )
        settings = rest
    return PerformerConfig(
        kind=kind,
        name=name.strip(),
        actions=parse_actions(config.get("actions"), f"{key}.actions"),
        heartbeat_period=positive(config.get("heartbeat_period", 1.0), f"{key}.heartbeat_period"),
        commit_timeout=positive(config.get("commit_timeout", 2.0), f"{key}.commit_timeout"),
        settings=settings,
        key=key,
        raw=config,
    )


def construct(cls: Any, entry: PerformerConfig, context: PerformerContext) -> Any:
    """``cls(context, name, actions, ..., settings=...)`` for a performer class
    ``cls`` (not imported here: the base class imports this module); a refusal of
    ``__init__`` is a ConfigError naming the entry."""
    kwargs = {"settings": entry.settings} if has_settings_model(cls) else dict(entry.settings)
    try:
        return cls(
            context,
            entry.name,
            entry.actions,
            heartbeat_period=entry.heartbeat_period,
            commit_timeout=entry.commit_timeout,
            **kwargs,
        )
    except ConfigError:
        raise
    except (PlansysBridgeError, TypeError, ValueError) as exc:
        raise ConfigError(str(exc), key=entry.key) from exc


def positive(value: object, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ConfigError(f"must be a number > 0, got {value!r}", key=key)
    return float(value)


def parse_actions(value: object, key: str) -> dict[str, tuple[str, ...]]:
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
