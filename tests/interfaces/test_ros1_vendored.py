"""The vendored upstream ROS 1 ``.msg`` texts against rosbags' ROS 1 Noetic store.

A ROS 1 peer refuses a connection whose md5sum differs from its own, so each text
vendored under ``plansys_bridge/interfaces/ros1`` that Noetic also ships (std_msgs,
geometry_msgs, nav_msgs, actionlib_msgs) must give the md5sum and the fields (names,
types, order) Noetic has, and the project's store must be built from those texts.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

pytest.importorskip("rosbags", reason="rosbags (extra 'rosbag') is not installed")

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from plansys_bridge.ros1.types import INTERFACES_DIR, Ros1Types

PACKAGES = ("std_msgs", "geometry_msgs", "nav_msgs", "actionlib_msgs")
FILES = sorted(p for pkg in PACKAGES for p in (INTERFACES_DIR / pkg / "msg").glob("*.msg"))
NOETIC = get_typestore(Stores.ROS1_NOETIC)


def _name(path: Path) -> str:
    return f"{path.parts[-3]}/msg/{path.stem}"


def _vendored_only() -> Typestore:
    """A store holding nothing but the vendored texts (and the builtin time types)."""
    store = get_typestore(Stores.EMPTY)
    types: dict[str, object] = {}
    for path in FILES:
        types.update(get_types_from_msg(path.read_text(encoding="utf-8"), _name(path)))
    store.register(types)  # type: ignore[arg-type]
    return store


VENDORED = _vendored_only()


def _text_field_names(text: str) -> list[str]:
    """Field names read straight from the text: ``type name`` lines, not constants."""
    names = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        match = re.fullmatch(r"\S+\s+(\w+)", line)
        if match:
            names.append(match.group(1))
    return names


def test_the_used_types_are_vendored() -> None:
    names = {_name(p) for p in FILES}
    for used in (
        "std_msgs/msg/Header",
        "std_msgs/msg/String",
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        "geometry_msgs/msg/Twist",
        "geometry_msgs/msg/TransformStamped",
        "nav_msgs/msg/Odometry",
        "actionlib_msgs/msg/GoalID",
        "actionlib_msgs/msg/GoalStatusArray",
    ):
        assert used in names
    for pkg in PACKAGES:
        assert (INTERFACES_DIR / pkg / "LICENSE").read_text().startswith("Software License")
        assert "Tag:" in (INTERFACES_DIR / pkg / "SOURCE.md").read_text()


@pytest.mark.parametrize("path", FILES, ids=_name)
def test_vendored_text_gives_noetic_md5_and_fields(path: Path) -> None:
    name = _name(path)
    assert name in NOETIC.fielddefs, f"{name} is not a Noetic type"
    text_def, text_md5 = VENDORED.generate_msgdef(name, ros_version=1)
    noetic_def, noetic_md5 = NOETIC.generate_msgdef(name, ros_version=1)
    assert text_md5 == noetic_md5
    assert text_def == noetic_def
    fields = [f for f, _ in VENDORED.fielddefs[name][1]]
    assert fields == [f for f, _ in NOETIC.fielddefs[name][1]]
    assert VENDORED.fielddefs[name][1] == NOETIC.fielddefs[name][1]
    # rosbags gives an empty message (std_msgs/Empty) one placeholder member.
    real = [f for f in fields if f != "structure_needs_at_least_one_member"]
    assert _text_field_names(path.read_text(encoding="utf-8")) == real


@pytest.mark.parametrize("path", FILES, ids=_name)
def test_project_store_uses_the_vendored_text(path: Path) -> None:
    name = _name(path)
    store = Ros1Types().store
    assert store.fielddefs[name] == VENDORED.fielddefs[name]
    assert Ros1Types.default().md5sum(name) == NOETIC.generate_msgdef(name, ros_version=1)[1]
