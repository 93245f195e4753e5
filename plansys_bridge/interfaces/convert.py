"""Python objects -> ROS 2 messages, field by field, from the ``.msg`` layouts.

A hub message (:mod:`plansys_bridge.hub.messages`) and its ROS 2 type share field
names, so one walk over the type's parsed fields converts it, whatever class builds
the ROS message: the generated Cyclone DDS types for the wire, rosbags' types for
bags. Enums become integers, float seconds ``builtin_interfaces/Time`` /
``Duration``, tuples lists, nested objects nested messages; fields the object lacks
keep the message's default. No layout is written out anywhere but in the ``.msg``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from plansys_bridge.interfaces.typestore import Nodetype, ros2_fielddefs

__all__ = ["DURATION", "TIME", "Encoder", "message_encoder"]

TIME = "builtin_interfaces/msg/Time"
DURATION = "builtin_interfaces/msg/Duration"
_FLOATS = {"float32", "float64"}

Encoder = Callable[[Any], Any]
MakeType = Callable[[str], Callable[..., Any]]
"""ROS 2 type name -> the class that builds its messages."""
SplitSeconds = Callable[[float, str], tuple[int, int]]
"""Float seconds (and what they are, for errors) -> ``(sec, nanosec)``."""


def message_encoder(ros_type: str, make: MakeType, split: SplitSeconds) -> Encoder:
    """An object -> ``make(ros_type)`` message converter (build once, use many times)."""
    cache: dict[str, Encoder] = {}
    return _encoder(ros_type, make, split, cache)


def _encoder(
    ros_type: str, make: MakeType, split: SplitSeconds, cache: dict[str, Encoder]
) -> Encoder:
    found = cache.get(ros_type)
    if found is not None:
        return found
    cls = make(ros_type)
    fields = [
        (name, _value(desc, make, split, cache)) for name, desc in ros2_fielddefs()[ros_type][1]
    ]

    def encode(obj: Any) -> Any:
        values = {}
        for name, convert in fields:
            value = getattr(obj, name, None)
            if value is not None:
                values[name] = convert(value)
        return cls(**values)

    cache[ros_type] = encode
    return encode


def _value(
    desc: tuple[Any, Any], make: MakeType, split: SplitSeconds, cache: dict[str, Encoder]
) -> Encoder:
    kind, detail = desc
    if kind == Nodetype.BASE:
        base = detail[0]
        if base == "string":
            return str
        if base == "bool":
            return bool
        return float if base in _FLOATS else int
    if kind == Nodetype.NAME:
        if detail in (TIME, DURATION):
            stamp = make(detail)
            what = "stamp" if detail == TIME else "duration"

            def seconds(value: float) -> Any:
                sec, nanosec = split(value, what)
                return stamp(sec=sec, nanosec=nanosec)

            return seconds
        return _encoder(detail, make, split, cache)
    element = _value(detail[0], make, split, cache)
    return lambda values: [element(v) for v in values]
