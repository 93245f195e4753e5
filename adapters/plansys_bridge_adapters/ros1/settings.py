"""The ``ros1_move_base`` mission entry: master, action namespace, frame, locations.

::

    performers:
      - kind: ros1_move_base
        name: tiago_nav
        actions: {move: [r1]}
        master_uri: http://127.0.0.1:11311   # default $ROS_MASTER_URI
        action_ns: /move_base                 # default
        frame_id: map                         # default
        target_arg: -1                        # the argument naming the destination
        locations: {hall: {x: 0.0, y: 0.0, yaw: 0.0}, kitchen: {x: 4.0, y: 1.0, yaw: 1.57}}

Every object the domain lets a served action go to must have a location: a missing
one is an error naming the key when the mission loads, not a failure mid-mission.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from plansys_bridge.errors import ConfigError
from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.master import check_uri
from plansys_bridge.ros1.node import DEFAULT_MASTER_URI, resolve_topic

from ..nav_goals import Pose2D, check_destinations, parse_locations, parse_target_arg

__all__ = ["SETTINGS_KEYS", "MoveBaseSettings", "Pose2D", "check_destinations", "parse_settings"]

SETTINGS_KEYS = frozenset({"master_uri", "action_ns", "frame_id", "target_arg", "locations"})


@dataclass(frozen=True)
class MoveBaseSettings:
    master_uri: str
    action_ns: str
    frame_id: str
    target_arg: int
    locations: dict[str, Pose2D]


def _string(value: object, key: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"must be a non-empty string, got {value!r}", key=key)
    return value.strip()


def parse_settings(raw: Mapping[str, Any], key: str) -> MoveBaseSettings:
    """Check the kind-specific keys; every error names its key."""
    master = raw.get("master_uri") or os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI
    try:
        master_uri = check_uri(_string(master, f"{key}.master_uri"))
        action_ns = resolve_topic(_string(raw.get("action_ns", "/move_base"), f"{key}.action_ns"))
    except Ros1Error as exc:
        which = "master_uri" if "master_uri" in str(exc) else "action_ns"
        raise ConfigError(str(exc), key=f"{key}.{which}") from exc
    frame_id = _string(raw.get("frame_id", "map"), f"{key}.frame_id")
    target = parse_target_arg(raw.get("target_arg", -1), f"{key}.target_arg")
    locations = parse_locations(raw.get("locations"), f"{key}.locations")
    return MoveBaseSettings(master_uri, action_ns, frame_id, target, locations)
