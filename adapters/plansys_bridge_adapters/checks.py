"""Checks shared by the adapters' configuration parsers; errors name the key."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from plansys_bridge.errors import ConfigError


def mapping(value: object, key: str, allowed: Iterable[str], hint: str) -> Mapping[str, Any]:
    """``value`` as a mapping whose keys are all in ``allowed``; ``hint`` says what it wants."""
    if not isinstance(value, Mapping):
        raise ConfigError(hint, key=key)
    names = sorted(allowed)
    for name in value:
        if name not in names:
            raise ConfigError(f"unknown key (allowed: {', '.join(names)})", key=f"{key}.{name}")
    return value


def positive(value: object, key: str) -> float:
    """A number > 0 (booleans are not numbers here)."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ConfigError(f"must be a number > 0, got {value!r}", key=key)
    return float(value)
