"""Errors that name their place in the mission file.

A refused knowledge change or a performer plugin's ``ConfigError`` knows what went
wrong but not where the user wrote it; these wrappers add the mission file and the
key (``knowledge.predicates[2]``), so one message says both.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.mission_config import MissionConfig

__all__ = ["in_mission_file", "keyed"]


@contextlib.contextmanager
def in_mission_file(mission: MissionConfig) -> Iterator[None]:
    """Add the mission file's name, and the line and column of the key, to a
    ConfigError that names only the key (the performer plugins check their
    settings knowing the key, not the file)."""
    try:
        yield
    except ConfigError as exc:
        located = mission.locate(exc)
        if located is exc:
            raise
        raise located from exc


@contextlib.contextmanager
def keyed(mission: MissionConfig, key: str) -> Iterator[None]:
    """Turn a refused change into a ConfigError naming the mission file's key."""
    try:
        yield
    except PlansysBridgeError as exc:
        raise mission.error(str(exc), key=key) from exc
