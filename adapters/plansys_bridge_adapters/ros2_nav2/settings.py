"""The ``ros2_nav2`` performer's mission settings: where each destination is.

``frame_id``, ``target_arg`` and ``locations`` are the ``ros1_move_base`` performer's
(:mod:`plansys_bridge_adapters.nav_goals`), so a mission moves from one to the other
by changing ``kind`` and the connection keys::

    - kind: ros2_nav2
      name: tb3_nav
      actions: {move: [r1]}
      action_name: navigate_to_pose   # default; the ROS 2 action (Nav2's bt_navigator)
      frame_id: map                   # default; the frame of the goal poses
      target_arg: -1                  # action argument naming the destination (default: last)
      locations: {hall: {x: 0.0, y: 0.0, yaw: 0.0}, kitchen: {x: 4.0, y: 1.0, yaw: 1.57}}
      domain_id: 0                    # default: the mission's DDS domain, else 0
      double: {speed: 1.0, blocked: []}  # optional: a Nav2 double on the domain

``locations`` is a mapping or a YAML file (relative to the mission file) holding one
(optionally under a ``locations:`` key). :class:`Nav2Settings` is validated when the
mission loads, an inline table included; :func:`resolve` reads a locations file and
checks the double's ``blocked`` names when the performer is built.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from pydantic import Field

from plansys_bridge.errors import ConfigError
from plansys_bridge.plugins import PluginSettings, validate_settings
from plansys_bridge.yaml_files import load_yaml_document

from ..nav_goals import LocationTable, NavGoalSettings, Pose2D, poses

__all__ = ["Nav2Double", "Nav2Settings", "NavSettings", "load_locations", "resolve"]


class Nav2Double(PluginSettings):
    """``double:``: run a NavigateToPose double on the performer's domain."""

    speed: float = Field(1.0, gt=0)
    """Metres per second of the pretend robot."""
    blocked: list[str] = Field(default_factory=list)
    """Location names whose goals the double aborts (no valid path)."""


class Nav2Settings(NavGoalSettings):
    """The kind-specific keys of a ``ros2_nav2`` entry."""

    locations_files: ClassVar[bool] = True

    action_name: str = Field("navigate_to_pose", pattern=r"[^/\s]")
    """The NavigateToPose action (Nav2's bt_navigator serves ``navigate_to_pose``)."""
    locations: LocationTable | str  # type: ignore[assignment]  # a file name too
    """``{name: {x, y, yaw}}``, or a YAML file holding it (read when built)."""
    domain_id: int | None = Field(None, ge=0)
    """Default: the mission's DDS domain, else 0."""
    double: Nav2Double | None = None


@dataclass(frozen=True)
class NavSettings:
    """What the performer runs with: :class:`Nav2Settings` with its file read."""

    action_name: str
    frame_id: str
    target_arg: int
    locations: Mapping[str, Pose2D]
    domain_id: int | None
    double: Nav2Double | None = None


def load_locations(value: str, key: str, base_dir: Path) -> dict[str, Pose2D]:
    """The table in the YAML file ``value`` (relative to the mission file), bare or
    under a ``locations:`` key; a bad entry is an error naming the file's line and
    column and the key path inside the file."""
    path = Path(value)
    path = path if path.is_absolute() else base_dir / path
    loaded, positions = load_yaml_document(path, "locations file", key)
    wrapped = isinstance(loaded, Mapping) and set(loaded) == {"locations"}
    try:
        table = validate_settings(NavGoalSettings, loaded if wrapped else {"locations": loaded})
    except ConfigError as exc:
        inner = exc.key if wrapped or exc.key is None else exc.key.partition(".")[2] or None
        raise positions.relocate(ConfigError(exc.reason, key=inner)) from exc
    return poses(table.locations)


def resolve(settings: Nav2Settings, key: str, base_dir: Path) -> NavSettings:
    """The performer's settings: a locations file read, the double's names checked."""
    where = f"{key}.locations"
    table = (
        load_locations(settings.locations, where, base_dir)
        if isinstance(settings.locations, str)
        else poses(settings.locations)
    )
    double = settings.double
    for i, name in enumerate(double.blocked if double is not None else ()):
        if name.strip().lower() not in table:
            raise ConfigError(
                f"{name!r} is not a location (known: {', '.join(sorted(table))})",
                key=f"{key}.double.blocked[{i}]",
            )
    return NavSettings(
        settings.action_name.strip(),
        settings.frame_id,
        settings.target_arg,
        table,
        settings.domain_id,
        double,
    )
