"""ROS 1 <-> ROS 2 message conversion, driven by the two typestores.

Types are named in ROS 2 form (``nav_msgs/msg/Odometry``). A ROS 1 message and its
ROS 2 counterpart have the same fields except where the two distributions differ:
``std_msgs/Header`` has ``seq`` in ROS 1 only; ROS 1 ``time``/``duration`` are
``builtin_interfaces`` Time/Duration in ROS 2 (rosbags represents both as
``sec``/``nanosec``). The converter walks the target type's fields, copies what the
source has, fills what it lacks with defaults, and sets ``Header.seq`` from a
per-topic counter towards ROS 1 (as roscpp and rospy publishers do). A field the
source has and the target lacks is dropped; a type whose field *types* disagree is
refused when the route is set up, not per message.
"""

from __future__ import annotations

from typing import Any, cast

from rosbags.typesys.store import Typestore

from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.types import Ros1Types, default_value, store_name

__all__ = ["Converter"]

_BASE, _NAME, _ARRAY, _SEQUENCE = 1, 2, 3, 4


class Converter:
    """Converts one message type between a ROS 1 and a ROS 2 typestore."""

    def __init__(self, type_name: str, ros1: Ros1Types, ros2: Typestore) -> None:
        self.type_name = store_name(type_name)
        self.ros1 = ros1
        self.ros2 = ros2
        if self.type_name not in ros2.fielddefs:
            raise Ros1Error(f"unknown ROS 2 message type {type_name!r}")
        ros1.check(self.type_name)
        self._check(self.type_name, set())

    def _check(self, name: str, seen: set[str]) -> None:
        if name in seen:
            return
        seen.add(name)
        one = dict(self.ros1.store.fielddefs[name][1])
        two = dict(self.ros2.fielddefs[name][1])
        for field, desc in two.items():
            other = one.get(field)
            if other is None:
                continue
            if _shape(desc) != _shape(other):
                raise Ros1Error(
                    f"{name}.{field} is {_shape(other)} in ROS 1 but {_shape(desc)} in ROS 2"
                )
            for sub in _nested(desc):
                if sub not in self.ros1.store.fielddefs or sub not in self.ros2.fielddefs:
                    raise Ros1Error(f"{name}.{field}: type {sub} is missing on one side")
                self._check(sub, seen)

    def to_ros2(self, msg: Any) -> Any:
        return _convert(msg, self.type_name, self.ros2, None)

    def to_ros1(self, msg: Any, seq: int = 0) -> Any:
        return _convert(msg, self.type_name, self.ros1.store, seq)


def _shape(desc: Any) -> str:
    kind, arg = desc
    if kind == _BASE:
        return str(arg[0])
    if kind == _NAME:
        return str(arg)
    (sub_kind, sub), count = arg
    inner = str(sub[0]) if sub_kind == _BASE else str(sub)
    return f"{inner}[{count if kind == _ARRAY else ''}]"


def _nested(desc: Any) -> list[str]:
    kind, arg = desc
    if kind == _NAME:
        return [arg]
    if kind in (_ARRAY, _SEQUENCE) and arg[0][0] == _NAME:
        return [arg[0][1]]
    return []


def _convert(msg: Any, name: str, target: Typestore, seq: int | None) -> Any:
    values: dict[str, Any] = {}
    for field, desc in target.fielddefs[name][1]:
        if name == "std_msgs/msg/Header" and field == "seq":
            values[field] = seq or 0
            continue
        if not hasattr(msg, field):
            values[field] = default_value(desc, target)
            continue
        value = getattr(msg, field)
        kind, arg = cast("tuple[int, Any]", desc)
        if kind == _NAME:
            values[field] = _convert(value, arg, target, seq)
        elif kind in (_ARRAY, _SEQUENCE) and arg[0][0] == _NAME:
            values[field] = [_convert(v, arg[0][1], target, seq) for v in value]
        else:
            values[field] = value
    return target.types[name](**values)
