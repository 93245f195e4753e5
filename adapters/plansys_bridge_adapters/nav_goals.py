"""What navigation performers share: named 2-D goal poses and the check that every
destination of a served action has one.

The ``ros1_move_base`` and ``ros2_nav2`` performers take the same mission keys,
``frame_id``, ``target_arg`` (the action argument naming the destination, -1 = last)
and ``locations`` (``{name: {x, y, yaw}}``), so a mission moves between ROS 1
move_base and ROS 2 Nav2 by changing ``kind`` and the connection keys.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from pydantic import Field

from plansys_bridge.errors import ConfigError
from plansys_bridge.pddl.types import TypeHierarchy
from plansys_bridge.plugins import PluginSettings

from .checks import mapping

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert

__all__ = [
    "NavGoalSettings",
    "Pose2D",
    "check_destinations",
    "parse_locations",
    "parse_target_arg",
]


class NavGoalSettings(PluginSettings):
    """The keys both navigation performers take (their ``Settings`` extend this)."""

    frame_id: str = Field("map", min_length=1)
    """The frame of the goal poses."""
    target_arg: int = -1
    """The action argument naming the destination (-1 = the last)."""
    locations: Any = Field(...)
    """``{name: {x, y, yaw}}``: where each destination is."""


@dataclass(frozen=True)
class Pose2D:
    """A place on the map: position in metres, heading (yaw) in radians."""

    x: float
    y: float
    yaw: float = 0.0

    def quaternion(self) -> tuple[float, float, float, float]:
        """``(x, y, z, w)`` of a rotation by ``yaw`` about z."""
        return (0.0, 0.0, math.sin(self.yaw / 2), math.cos(self.yaw / 2))


def _number(value: object, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"must be a finite number, got {value!r}", key=key)
    return float(value)


def parse_target_arg(value: object, key: str) -> int:
    """``target_arg``: which action argument names the destination (-1 = the last)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"must be an argument index (e.g. -1 = last), got {value!r}", key=key)
    return value


def parse_locations(places: object, where: str) -> dict[str, Pose2D]:
    """``{name: {x, y, yaw}}`` (names case-insensitive); errors name the key under ``where``."""
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
    return locations


class _Destinations(Protocol):
    @property
    def target_arg(self) -> int: ...

    @property
    def locations(self) -> Mapping[str, Pose2D]: ...


def check_destinations(
    settings: _Destinations,
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
