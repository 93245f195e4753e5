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

``locations`` is a mapping or a YAML file (relative to the mission file) holding one.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plansys_bridge.errors import ConfigError

from ..checks import mapping, positive
from ..nav_goals import Pose2D, parse_locations, parse_target_arg

__all__ = ["NavSettings", "load_locations"]


def load_locations(value: object, key: str, base_dir: Path) -> dict[str, Pose2D]:
    """``{name: {x, y, yaw}}`` inline, or the name of a YAML file holding that mapping
    (optionally under a ``locations:`` key), relative to the mission file."""
    if isinstance(value, str):
        from plansys_bridge.yaml_files import load_yaml_file

        path = base_dir / value
        value = load_yaml_file(path, "locations file", key)
        if isinstance(value, Mapping) and set(value) == {"locations"}:
            value = value["locations"]
        key = str(path)
    return parse_locations(value, key)


@dataclass(frozen=True)
class NavSettings:
    """The checked settings of one ``ros2_nav2`` performer."""

    action_name: str
    frame_id: str
    target_arg: int
    locations: Mapping[str, Pose2D]
    domain_id: int | None
    double: Mapping[str, Any] | None

    @classmethod
    def parse(cls, settings: Mapping[str, Any], key: str, base_dir: Path) -> NavSettings:
        action = settings.get("action_name", "navigate_to_pose")
        if not isinstance(action, str) or not action.strip("/ "):
            raise ConfigError("expected an action name", key=f"{key}.action_name")
        frame = settings.get("frame_id", "map")
        if not isinstance(frame, str) or not frame:
            raise ConfigError("expected a frame id", key=f"{key}.frame_id")
        target = parse_target_arg(settings.get("target_arg", -1), f"{key}.target_arg")
        locations = load_locations(settings.get("locations"), f"{key}.locations", base_dir)
        domain = settings.get("domain_id")
        if domain is not None and (isinstance(domain, bool) or not isinstance(domain, int)):
            raise ConfigError("expected a DDS domain id", key=f"{key}.domain_id")
        double = settings.get("double")
        if double is not None:
            double = mapping(
                double, f"{key}.double", ("speed", "blocked"), "expected {speed, blocked}"
            )
            positive(double.get("speed", 1.0), f"{key}.double.speed")
            blocked = double.get("blocked", [])
            if not isinstance(blocked, list) or any(
                not isinstance(b, str) or b.lower() not in locations for b in blocked
            ):
                raise ConfigError(
                    "expected a list of location names whose goals the double aborts",
                    key=f"{key}.double.blocked",
                )
        return cls(action.strip(), frame, target, locations, domain, double)
