"""Field-by-field conversion between hub dataclasses and generated DDS types.

A hub message (:mod:`plansys_bridge.hub.messages`) and its ROS 2 type share field
names; the converters here are built once per pair from the type's parsed ``.msg``
fields, so no layout is written twice. On the way out, enums become integers, float
seconds become ``builtin_interfaces/Time`` / ``Duration`` and tuples become lists; on
the way in the reverse, with the checks a foreign writer may fail: an integer outside
the enum's constants or a non-finite number raises ``ValueError`` naming the field.
"""

from __future__ import annotations

import dataclasses
import enum
import math
import typing
from collections.abc import Callable
from functools import cache
from typing import Any

from plansys_bridge.errors import HubError
from plansys_bridge.interfaces.convert import DURATION, TIME, Encoder, message_encoder
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.interfaces.typestore import Nodetype, ros2_fielddefs

__all__ = [
    "Decoder",
    "Encoder",
    "from_idl_seconds",
    "hub_decoder",
    "hub_encoder",
    "split_seconds",
    "to_idl_duration",
    "to_idl_time",
]

Decoder = Callable[[Any], Any]

_INT32 = (-(2**31), 2**31 - 1)
_FLOATS = {"float32", "float64"}


def split_seconds(seconds: float, what: str) -> tuple[int, int]:
    if not math.isfinite(seconds):
        raise HubError(f"{what} {seconds!r} is not a finite number of seconds")
    sec = math.floor(seconds)
    nanosec = round((seconds - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    if not _INT32[0] <= sec <= _INT32[1]:
        raise HubError(f"{what} {seconds!r} s does not fit builtin_interfaces (int32 seconds)")
    return int(sec), int(nanosec)


def to_idl_time(seconds: float) -> Any:
    sec, nanosec = split_seconds(seconds, "stamp")
    return dds_type(TIME)(sec=sec, nanosec=nanosec)


def to_idl_duration(seconds: float) -> Any:
    sec, nanosec = split_seconds(seconds, "duration")
    return dds_type(DURATION)(sec=sec, nanosec=nanosec)


def from_idl_seconds(value: Any) -> float:
    return float(value.sec + value.nanosec * 1e-9)


@cache
def hub_encoder(ros_type: str) -> Encoder:
    """hub dataclass -> the DDS sample of ``ros_type``; fields the hub lacks keep defaults."""
    return message_encoder(ros_type, dds_type, split_seconds)


def _finite(name: str) -> Decoder:
    def check(value: Any) -> float:
        number = float(value)
        if not math.isfinite(number):
            raise ValueError(f"{name} is {number!r}, not a finite number")
        return number

    return check


def _enum(name: str, cls: type[enum.IntEnum]) -> Decoder:
    def check(value: Any) -> enum.IntEnum:
        try:
            return cls(value)
        except ValueError:
            known = ", ".join(f"{m.name}={m.value}" for m in cls)
            raise ValueError(f"{name} is {value!r}, not one of {known}") from None

    return check


def _in_value(name: str, hint: Any, desc: tuple[Any, Any]) -> Decoder:
    kind, detail = desc
    if kind in (Nodetype.SEQUENCE, Nodetype.ARRAY):
        element_hint = typing.get_args(hint)[0] if typing.get_args(hint) else Any
        element = _in_value(name, element_hint, detail[0])
        return lambda values: tuple(element(v) for v in values)
    if kind == Nodetype.NAME:
        if detail in (TIME, DURATION):
            return from_idl_seconds
        return hub_decoder(hint, detail)
    if isinstance(hint, type) and issubclass(hint, enum.IntEnum):
        return _enum(name, hint)
    if detail[0] in _FLOATS:
        return _finite(name)
    return lambda value: value


@cache
def hub_decoder(hub_class: type, ros_type: str) -> Decoder:
    """DDS sample of ``ros_type`` -> ``hub_class`` (fields it does not carry get defaults)."""
    hints = typing.get_type_hints(hub_class)
    known = {f.name for f in dataclasses.fields(hub_class)}
    fields = [
        (name, _in_value(f"{ros_type}.{name}", hints[name], desc))
        for name, desc in ros2_fielddefs()[ros_type][1]
        if name in known
    ]

    def decode(sample: Any) -> Any:
        return hub_class(**{name: convert(getattr(sample, name)) for name, convert in fields})

    return decode
