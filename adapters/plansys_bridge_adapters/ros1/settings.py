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

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from plansys_bridge.errors import ConfigError
from plansys_bridge.pddl.types import TypeHierarchy
from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.master import check_uri
from plansys_bridge.ros1.node import DEFAULT_MASTER_URI, resolve_topic

from ..checks import mapping

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert

__all__ = ["SETTINGS_KEYS", "MoveBaseSettings", "Pose2D", "check_destinations", "parse_settings"]

SETTINGS_KEYS = frozenset({"master_uri", "action_ns", "frame_id", "target_arg", "locations"})


@dataclass(frozen=True)
class Pose2D:
    """A place on the map: position in metres, heading (yaw) in radians."""

    x: float
    y: float
    yaw: float = 0.0

    def quaternion(self) -> tuple[float, float, float, float]:
        """``(x, y, z, w)`` of a rotation by ``yaw`` about z."""
        return (0.0, 0.0, math.sin(self.yaw / 2), math.cos(self.yaw / 2))


@dataclass(frozen=True)
class MoveBaseSettings:
    master_uri: str
    action_ns: str
    frame_id: str
    target_arg: int
    locations: dict[str, Pose2D]


def _number(value: object, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"must be a finite number, got {value!r}", key=key)
    return float(value)


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
    target = raw.get("target_arg", -1)
    if isinstance(target, bool) or not isinstance(target, int):
        raise ConfigError(
            f"must be an argument index (e.g. -1 = last), got {target!r}", key=f"{key}.target_arg"
        )
    where = f"{key}.locations"
    places = raw.get("locations")
    if not isinstance(places, Mapping) or not places:
        raise ConfigError(
            "must map each destination to {x, y, yaw}, e.g. {kitchen: {x: 4.0, y: 1.0, yaw: 1.57}}",
            key=where,
        )
    locations: dict[str, Pose2D] = {}
    for name, spec in places.items():
        here = f"{where}.{name}"
        if not isinstance(name, str) or not name.strip():
            raise ConfigError(f"destination names must be strings, got {name!r}", key=where)
        pose = mapping(spec, here, ("x", "y", "yaw"), "must be {x: M, y: M, yaw: RAD}")
        for axis in ("x", "y"):
            if axis not in pose:
                raise ConfigError(f"missing {axis}", key=here)
        lname = name.strip().lower()
        if lname in locations:
            raise ConfigError(
                f"destination {lname!r} given twice (names are case-insensitive)", key=here
            )
        locations[lname] = Pose2D(
            _number(pose["x"], f"{here}.x"),
            _number(pose["y"], f"{here}.y"),
            _number(pose.get("yaw", 0.0), f"{here}.yaw"),
        )
    return MoveBaseSettings(master_uri, action_ns, frame_id, target, locations)


def check_destinations(
    settings: MoveBaseSettings,
    actions: Mapping[str, tuple[str, ...]],
    knowledge: ProblemExpert | None,
    key: str,
) -> None:
    """Every object a served action can be sent to has a location (else ConfigError)."""
    if knowledge is None:
        return
    domain = knowledge.domain
    hierarchy = TypeHierarchy(domain)
    by_name = {a.name: a for a in domain.actions}
    objects = dict(knowledge.get_instances())
    objects.update({c.name: c.types[0] for c in domain.constants})
    for action_name in actions:
        action = by_name.get(action_name)
        if action is None:
            continue
        params = action.parameters
        index = settings.target_arg
        if not -len(params) <= index < len(params):
            raise ConfigError(
                f"action {action_name} has {len(params)} parameters; no argument {index}",
                key=f"{key}.target_arg",
            )
        param = params[index]
        for obj, obj_type in sorted(objects.items()):
            if obj.lower() in settings.locations:
                continue
            if hierarchy.is_subtype_of_any((obj_type,), param.types):
                raise ConfigError(
                    f"no location for {obj!r}, a {obj_type} that {action_name} can go to "
                    f"({param.name}); known: {', '.join(sorted(settings.locations))}",
                    key=f"{key}.locations",
                )
