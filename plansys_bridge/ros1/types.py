"""ROS 1 message types: serialisation, md5sum and message_definition from rosbags.

TCPROS peers refuse a connection whose md5sum differs from theirs, and rospy
rebuilds nothing from ``message_definition`` but tools (rosbag, rqt) do, so both
must be what genmsg would produce; rosbags computes both the way genmsg does. The
types the bridge uses (std_msgs, geometry_msgs, nav_msgs, actionlib_msgs,
move_base_msgs, tf2_msgs) are read from the upstream ``.msg``/``.action`` texts
vendored under ``plansys_bridge/interfaces/ros1``, so those texts are what peers
see; the rest of rosbags' ROS 1 Noetic store (sensor_msgs, ...) is added after
them, and further custom types can be registered from ``.msg`` text.

Names are accepted in ROS 1 form (``std_msgs/String``) and ROS 2 form
(``std_msgs/msg/String``); the store keys on the ROS 2 form.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from plansys_bridge.ros1.errors import Ros1Error

__all__ = [
    "INTERFACES_DIR",
    "Ros1Types",
    "action_texts",
    "default_value",
    "ros1_name",
    "store_name",
]

_BASE, _NAME, _ARRAY = 1, 2, 3
"""rosbags' field kinds (Nodetype): a base type, a named message, a fixed array."""

INTERFACES_DIR = Path(__file__).resolve().parents[1] / "interfaces" / "ros1"
"""Vendored upstream ROS 1 interface texts, one folder per package (see SOURCE.md there)."""


def store_name(name: str) -> str:
    """``std_msgs/String`` or ``std_msgs/msg/String`` -> ``std_msgs/msg/String``."""
    parts = [p for p in name.strip().split("/") if p]
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    if len(parts) == 3 and parts[1] == "msg":
        return "/".join(parts)
    raise Ros1Error(f"not a message type name: {name!r} (expected pkg/Type or pkg/msg/Type)")


def ros1_name(name: str) -> str:
    """The name ROS 1 peers use in connection headers: ``std_msgs/String``."""
    pkg, _, typ = store_name(name).split("/")
    return f"{pkg}/{typ}"


def action_texts(pkg: str, action: str, text: str) -> dict[str, str]:
    """The seven messages actionlib's genaction makes of a ``.action`` text."""
    parts = re.split(r"^---[ \t]*$", text, flags=re.MULTILINE)
    if len(parts) != 3:
        raise Ros1Error(f"{pkg}/{action}.action: expected goal, result and feedback parts")
    goal, result, feedback = (p.strip() + "\n" for p in parts)
    return {
        f"{action}Goal": goal,
        f"{action}Result": result,
        f"{action}Feedback": feedback,
        f"{action}ActionGoal": f"Header header\nactionlib_msgs/GoalID goal_id\n{action}Goal goal\n",
        f"{action}ActionResult": (
            f"Header header\nactionlib_msgs/GoalStatus status\n{action}Result result\n"
        ),
        f"{action}ActionFeedback": (
            f"Header header\nactionlib_msgs/GoalStatus status\n{action}Feedback feedback\n"
        ),
        f"{action}Action": (
            f"{action}ActionGoal action_goal\n{action}ActionResult action_result\n"
            f"{action}ActionFeedback action_feedback\n"
        ),
    }


def _vendored_texts(root: Path) -> dict[str, str]:
    texts: dict[str, str] = {}
    for path in sorted(root.glob("*/msg/*.msg")):
        texts[f"{path.parts[-3]}/msg/{path.stem}"] = path.read_text(encoding="utf-8")
    for path in sorted(root.glob("*/action/*.action")):
        pkg = path.parts[-3]
        generated = action_texts(pkg, path.stem, path.read_text(encoding="utf-8"))
        texts.update({f"{pkg}/msg/{name}": body for name, body in generated.items()})
    return texts


def default_value(desc: Any, store: Typestore) -> Any:
    """The zero value of a field described by ``desc`` (rosbags' field description)."""
    kind, arg = desc
    if kind == _BASE:
        return "" if arg[0] == "string" else False if arg[0] == "bool" else 0
    if kind == _NAME:
        fields = store.fielddefs[arg][1]
        return store.types[arg](**{f: default_value(d, store) for f, d in fields})
    (sub_kind, sub), count = arg
    length = count if kind == _ARRAY else 0
    if sub_kind == _BASE and sub[0] != "string":
        return np.zeros(length, dtype=_NUMPY.get(sub[0], "float64"))
    return [default_value((sub_kind, sub), store) for _ in range(length)]


class Ros1Types:
    """One typestore with the ROS 1 definitions, and the TCPROS view of each type."""

    def __init__(self) -> None:
        self._defs: dict[str, tuple[str, str]] = {}
        self.store: Typestore = get_typestore(Stores.EMPTY)
        self.register_texts(_vendored_texts(INTERFACES_DIR))
        noetic = get_typestore(Stores.ROS1_NOETIC).fielddefs
        self.store.register({k: v for k, v in noetic.items() if k not in self.store.fielddefs})

    @classmethod
    @functools.cache
    def default(cls) -> Ros1Types:
        """The shared store (Noetic plus the vendored texts)."""
        return cls()

    def register_texts(self, texts: dict[str, str]) -> None:
        """Add custom types, ``{"pkg/msg/Type": ".msg text"}`` (ROS 1 syntax)."""
        types: dict[str, Any] = {}
        for name, text in texts.items():
            try:
                types.update(get_types_from_msg(text, store_name(name)))
            except Exception as exc:
                raise Ros1Error(f"message type {name}: cannot parse its .msg text: {exc}") from exc
        try:
            self.store.register(types)
        except Exception as exc:
            raise Ros1Error(f"cannot register message types: {exc}") from exc
        self._defs.clear()

    def known(self, name: str) -> bool:
        return store_name(name) in self.store.fielddefs

    def check(self, name: str) -> str:
        """The store name of ``name``; Ros1Error naming it if the store lacks it."""
        key = store_name(name)
        if key not in self.store.fielddefs:
            raise Ros1Error(
                f"unknown ROS 1 message type {name!r}: register its .msg text "
                "(Ros1Types.register_texts) or check the spelling"
            )
        return key

    def definition(self, name: str) -> tuple[str, str]:
        """``(message_definition, md5sum)`` as genmsg computes them."""
        key = self.check(name)
        found = self._defs.get(key)
        if found is None:
            found = self.store.generate_msgdef(key, ros_version=1)
            self._defs[key] = found
        return found

    def md5sum(self, name: str) -> str:
        return self.definition(name)[1]

    def message_class(self, name: str) -> Any:
        return self.store.types[self.check(name)]

    def new(self, name: str, **fields: Any) -> Any:
        """A message with every field defaulted (zeros, empty strings, nested defaults)."""
        key = self.check(name)
        values: dict[str, Any] = {}
        for field, desc in self.store.fielddefs[key][1]:
            if field in fields:
                values[field] = fields.pop(field)
            else:
                values[field] = default_value(desc, self.store)
        if fields:
            raise Ros1Error(f"{name} has no field(s) {', '.join(sorted(fields))}")
        return self.store.types[key](**values)

    def serialize(self, msg: object, name: str) -> bytes:
        try:
            return bytes(self.store.serialize_ros1(msg, self.check(name)))
        except Ros1Error:
            raise
        except Exception as exc:
            raise Ros1Error(f"cannot serialise a {name}: {exc}") from exc

    def deserialize(self, raw: bytes | memoryview, name: str) -> Any:
        try:
            return self.store.deserialize_ros1(raw, self.check(name))
        except Ros1Error:
            raise
        except Exception as exc:
            raise Ros1Error(f"cannot deserialise a {name}: {exc}") from exc


_NUMPY = {
    "bool": "bool",
    "byte": "uint8",
    "char": "uint8",
    "int8": "int8",
    "uint8": "uint8",
    "int16": "int16",
    "uint16": "uint16",
    "int32": "int32",
    "uint32": "uint32",
    "int64": "int64",
    "uint64": "uint64",
    "float32": "float32",
    "float64": "float64",
}
