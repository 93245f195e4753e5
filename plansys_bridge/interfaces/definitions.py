"""The vendored ROS interface texts, read as one message definition per ROS type name.

The project ships upstream's ``.msg``, ``.srv`` and ``.action`` files unchanged under
``plansys_bridge/interfaces/ros2/<pkg>/{msg,srv,action}/`` (each package folder names
its origin and licence in ``SOURCE.md``). Everything that needs a message layout (the
rosbags typestore for bags and MCAP schemas, the Cyclone DDS types of the hub) is
generated from these texts, so the layouts cannot drift apart.

A service ``pkg/srv/Name`` gives the messages ``pkg/srv/Name_Request`` and
``pkg/srv/Name_Response``. An action ``pkg/action/Name`` gives ``Name_Goal``,
``Name_Result`` and ``Name_Feedback`` plus the messages ROS 2 derives from them for
the wire (rosidl's action definition): ``Name_SendGoal_Request`` /
``Name_SendGoal_Response``, ``Name_GetResult_Request`` / ``Name_GetResult_Response``
and ``Name_FeedbackMessage``.

This module needs nothing beyond the standard library.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from plansys_bridge.errors import PlansysBridgeError

__all__ = [
    "ROS2_ROOT",
    "Definition",
    "InterfaceError",
    "parts_of",
    "ros2_definitions",
]

ROS2_ROOT = Path(__file__).resolve().parent / "ros2"
"""Where the ROS 2 interface packages are vendored."""

_SEPARATOR = re.compile(r"^---[ \t]*$", re.MULTILINE)


class InterfaceError(PlansysBridgeError):
    """A vendored interface file is missing or malformed, or a type name is unknown."""


@dataclass(frozen=True)
class Definition:
    """One message of a ROS interface package.

    ``text`` is ``.msg`` syntax. For the parts of a service or action it is the part
    of the file between ``---`` lines; for the derived action messages it is written
    here after rosidl's rules. Relative type names in ``text`` mean ``pkg/msg/...``.
    """

    name: str
    """The ROS 2 type name, e.g. ``plansys2_msgs/msg/ActionExecution``."""
    text: str
    source: Path
    """The vendored file the definition comes from."""


def parts_of(text: str, source: Path, count: int) -> list[str]:
    """Split a ``.srv`` (2 parts) or ``.action`` (3 parts) text at its ``---`` lines."""
    parts = _SEPARATOR.split(text)
    if len(parts) != count:
        raise InterfaceError(
            f"{source}: expected {count} parts separated by '---' lines, found {len(parts)}"
        )
    return [p.strip("\n") + "\n" if p.strip() else "" for p in parts]


def _action_messages(pkg: str, name: str) -> dict[str, str]:
    """The messages ROS 2 derives from an action for its services and feedback topic."""
    base = f"{pkg}/action/{name}"
    uuid = "unique_identifier_msgs/UUID goal_id\n"
    return {
        f"{base}_SendGoal_Request": f"{uuid}{base}_Goal goal\n",
        f"{base}_SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp\n",
        f"{base}_GetResult_Request": uuid,
        f"{base}_GetResult_Response": f"int8 status\n{base}_Result result\n",
        f"{base}_FeedbackMessage": f"{uuid}{base}_Feedback feedback\n",
    }


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InterfaceError(f"{path}: cannot read interface file: {exc}") from exc


def _package_definitions(pkg_dir: Path) -> list[Definition]:
    pkg = pkg_dir.name
    found: list[Definition] = []
    for path in sorted(pkg_dir.glob("msg/*.msg")):
        found.append(Definition(f"{pkg}/msg/{path.stem}", _read(path), path))
    for path in sorted(pkg_dir.glob("srv/*.srv")):
        request, response = parts_of(_read(path), path, 2)
        base = f"{pkg}/srv/{path.stem}"
        found.append(Definition(f"{base}_Request", request, path))
        found.append(Definition(f"{base}_Response", response, path))
    for path in sorted(pkg_dir.glob("action/*.action")):
        goal, result, feedback = parts_of(_read(path), path, 3)
        base = f"{pkg}/action/{path.stem}"
        for suffix, text in (("_Goal", goal), ("_Result", result), ("_Feedback", feedback)):
            found.append(Definition(base + suffix, text, path))
        for derived, text in _action_messages(pkg, path.stem).items():
            found.append(Definition(derived, text, path))
    return found


@cache
def ros2_definitions(root: Path = ROS2_ROOT) -> dict[str, Definition]:
    """Every ROS 2 message of the vendored packages under ``root``, by type name."""
    if not root.is_dir():
        raise InterfaceError(f"{root}: the vendored ROS 2 interfaces are missing")
    definitions: dict[str, Definition] = {}
    for pkg_dir in sorted(p for p in root.iterdir() if p.is_dir()):
        for definition in _package_definitions(pkg_dir):
            definitions[definition.name] = definition
    return definitions
