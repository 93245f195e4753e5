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

The location table, ``master_uri`` and ``action_ns`` are part of
:class:`MoveBaseEntry`, so a malformed one is an error when the mission loads,
naming file:line:col and the key path. Every object the domain lets a served action
go to must have a location: a missing one is an error naming the key when the
performer is built, not a failure mid-mission.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from pydantic import Field, field_validator

from plansys_bridge.errors import ConfigError
from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.master import check_uri
from plansys_bridge.ros1.node import DEFAULT_MASTER_URI, resolve_topic

from ..nav_goals import NavGoalSettings, Pose2D, check_destinations, poses

__all__ = ["MoveBaseEntry", "MoveBaseSettings", "Pose2D", "check_destinations", "resolve"]


class MoveBaseEntry(NavGoalSettings):
    """The kind-specific keys of a ``ros1_move_base`` entry."""

    master_uri: str | None = Field(None, min_length=1)
    """Default: ``$ROS_MASTER_URI``, else the local master."""
    action_ns: str = Field("/move_base", min_length=1)

    @field_validator("master_uri")
    @classmethod
    def _master_uri(cls, value: str | None) -> str | None:
        """A mistyped URI is a load-time error placed at its line, not a failure
        when the performer is built after the mission has started loading others."""
        if value is None:
            return None
        try:
            return check_uri(value.strip())
        except Ros1Error as exc:
            raise ValueError(str(exc)) from exc

    @field_validator("action_ns")
    @classmethod
    def _action_ns(cls, value: str) -> str:
        try:
            return resolve_topic(value.strip())
        except Ros1Error as exc:
            raise ValueError(str(exc)) from exc


@dataclass(frozen=True)
class MoveBaseSettings:
    master_uri: str
    action_ns: str
    frame_id: str
    target_arg: int
    locations: dict[str, Pose2D]


def resolve(entry: MoveBaseEntry, key: str) -> MoveBaseSettings:
    """The master's URI and the action namespace checked, the locations read."""
    master = entry.master_uri or os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI
    try:
        master_uri = check_uri(master.strip())
    except Ros1Error as exc:
        raise ConfigError(str(exc), key=f"{key}.master_uri") from exc
    try:
        action_ns = resolve_topic(entry.action_ns.strip())
    except Ros1Error as exc:
        raise ConfigError(str(exc), key=f"{key}.action_ns") from exc
    return MoveBaseSettings(
        master_uri, action_ns, entry.frame_id, entry.target_arg, poses(entry.locations)
    )
