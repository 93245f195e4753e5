"""Small checks shared by the settings dataclasses of the hub and the performers.

Settings come from mission YAML files, so every rejection names the key it is about
(``auction.retry_period``, ``performers[1].faults.die_rate``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields
from typing import Any, TypeVar, cast

from plansys_bridge.errors import ConfigError

__all__ = ["is_number", "settings_from_mapping"]


D = TypeVar("D")


def is_number(value: object) -> bool:
    """A finite int or float (YAML's ``true`` is not a number here)."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def settings_from_mapping(cls: type[D], config: object, key: str) -> D:
    """Build the settings dataclass ``cls`` from a mapping, rejecting unknown keys.

    ``cls.__post_init__`` raises ``ConfigError(key=<field>)``; the key is prefixed
    here with where the mapping sits in the file.
    """
    if config is None:
        return cls()
    if not isinstance(config, Mapping):
        raise ConfigError("expected a mapping of settings", key=key)
    known = {f.name for f in fields(cast(Any, cls))}
    for name in config:
        if name not in known:
            raise ConfigError(
                f"unknown setting (expected one of {', '.join(sorted(known))})",
                key=f"{key}.{name}",
            )
    try:
        return cls(**dict(config))
    except ConfigError as exc:
        field_name = (exc.key or "").rpartition(".")[2]
        message = str(exc).split(": ", 1)[-1]
        raise ConfigError(message, key=f"{key}.{field_name}" if field_name else key) from exc
