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
from typing import TYPE_CHECKING, Annotated, ClassVar, Protocol

from pydantic import Field, field_validator

from plansys_bridge.errors import ConfigError
from plansys_bridge.pddl.types import TypeHierarchy
from plansys_bridge.plugins import PluginSettings

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert

__all__ = [
    "LocationPose",
    "LocationTable",
    "NavGoalSettings",
    "Pose2D",
    "check_destinations",
    "check_table",
    "poses",
]


@dataclass(frozen=True)
class Pose2D:
    """A place on the map: position in metres, heading (yaw) in radians."""

    x: float
    y: float
    yaw: float = 0.0

    def quaternion(self) -> tuple[float, float, float, float]:
        """``(x, y, z, w)`` of a rotation by ``yaw`` about z."""
        return (0.0, 0.0, math.sin(self.yaw / 2), math.cos(self.yaw / 2))


class LocationPose(PluginSettings):
    """``{x, y, yaw?}``: one destination, in metres and radians in ``frame_id``."""

    x: float
    y: float
    yaw: float = 0.0


LocationTable = Annotated[dict[str, LocationPose], Field(min_length=1)]
"""``{name: {x, y, yaw}}``, names case-insensitive."""

TABLE_SHAPE = (
    "must map each destination to {x, y, yaw}, e.g. {kitchen: {x: 4.0, y: 1.0, yaw: 1.57}}"
)


def check_table(value: object, *, files: bool = False) -> object:
    """The table's shape, before pydantic checks each pose: one clear error for a
    value that is no mapping (or, with ``files``, no file name), a name that is no
    string, or a name given twice in different case."""
    if files and isinstance(value, str):
        if not value.strip():
            raise ValueError("must name a locations file or be a mapping of locations")
        return value
    if not isinstance(value, Mapping):
        also = " (or name a YAML file holding that mapping)" if files else ""
        raise ValueError(f"{TABLE_SHAPE}{also}; got {value!r}")
    seen: set[str] = set()
    for name in value:
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"destination names must be non-empty strings, got {name!r}")
        lowered = name.strip().lower()
        if lowered in seen:
            raise ValueError(f"destination {lowered!r} given twice (names are case-insensitive)")
        seen.add(lowered)
    return value


def poses(table: Mapping[str, LocationPose]) -> dict[str, Pose2D]:
    """A validated table as the performers look destinations up: by lower-case name."""
    return {name.strip().lower(): Pose2D(p.x, p.y, p.yaw) for name, p in table.items()}


class NavGoalSettings(PluginSettings):
    """The keys both navigation performers take (their ``Settings`` extend this).

    The location table is checked here, with the rest of the entry, so a bad pose is
    an error when the mission loads (file:line:col and key path), not when the
    performer is built."""

    locations_files: ClassVar[bool] = False
    """Whether ``locations`` may instead name a YAML file holding the table."""

    frame_id: str = Field("map", min_length=1)
    """The frame of the goal poses."""
    target_arg: int = -1
    """The action argument naming the destination (-1 = the last)."""
    locations: LocationTable
    """``{name: {x, y, yaw}}``: where each destination is."""

    @field_validator("locations", mode="before")
    @classmethod
    def _table_shape(cls, value: object) -> object:
        return check_table(value, files=cls.locations_files)


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
