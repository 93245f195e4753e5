"""Cyclone DDS types for ROS 2 messages, generated from the vendored ``.msg`` texts.

ROS 2 (rmw_cyclonedds) names the DDS type of ``pkg/msg/Name`` ``pkg::msg::dds_::Name_``
(services ``pkg::srv::dds_::Name_Request_``, actions ``pkg::action::dds_::Name_Goal_``
and so on), lays out its fields in ``.msg`` order with rosidl's IDL mapping
(``byte`` -> octet, ``char`` -> uint8, ``T[N]`` -> array, ``T[]`` / ``T[<=N]`` ->
sequence, ``string<=N`` -> bounded string, an empty message -> one uint8 member) and
serialises XCDR1 little-endian. :func:`dds_type` builds exactly that as a
``cyclonedds.idl.IdlStruct`` class for any type of the project's typestore
(:func:`plansys_bridge.interfaces.typestore.ros2_typestore`), nested types included;
classes are made once and reused, so one type name always gives the same class.

Constants (``int16 REQUEST=1``) are not part of a DDS type, as in ROS 2; they are in
the typestore's field definitions (:func:`ros2_constants`).
"""

from __future__ import annotations

import dataclasses
import threading
from typing import Any

from plansys_bridge.errors import PluginError
from plansys_bridge.interfaces.definitions import InterfaceError
from plansys_bridge.interfaces.typestore import Nodetype, ros2_fielddefs

try:
    from cyclonedds.idl import IdlMeta, IdlStruct
    from cyclonedds.idl import types as idl
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise PluginError("DDS types need cyclonedds: pip install 'plansys-bridge[dds]'") from exc

__all__ = ["dds_type", "dds_type_name", "ros2_constants"]

_BASE: dict[str, Any] = {
    "bool": bool,
    "byte": idl.byte,
    "char": idl.uint8,
    "int8": idl.int8,
    "uint8": idl.uint8,
    "int16": idl.int16,
    "uint16": idl.uint16,
    "int32": idl.int32,
    "uint32": idl.uint32,
    "int64": idl.int64,
    "uint64": idl.uint64,
    "float32": idl.float32,
    "float64": idl.float64,
    "string": str,
}
"""rosidl's mapping of ``.msg`` primitive types to IDL (rosidl_adapter's MSG_TYPE_TO_IDL)."""

_ZERO: dict[str, Any] = {"bool": False, "string": "", "float32": 0.0, "float64": 0.0}

# Cyclone's generic markers, indexed at run time (their stubs do not declare them generic).
_ARRAY: Any = idl.array
_SEQUENCE: Any = idl.sequence
_BOUNDED_STR: Any = idl.bounded_str

_lock = threading.RLock()
_classes: dict[str, type[IdlStruct]] = {}


def dds_type_name(name: str) -> str:
    """``std_msgs/msg/String`` -> ``std_msgs::msg::dds_::String_`` (ROS 2's DDS type name)."""
    parts = name.split("/")
    if len(parts) != 3 or not all(parts):
        raise InterfaceError(f"{name!r} is not a ROS 2 type name like 'std_msgs/msg/String'")
    pkg, kind, base = parts
    return f"{pkg}::{kind}::dds_::{base}_"


def dds_type(name: str) -> type[Any]:
    """The Cyclone DDS ``IdlStruct`` class of the ROS 2 message type ``name``.

    ``name`` is a ROS 2 type name known to the typestore: ``std_msgs/msg/String``,
    ``nav_msgs/msg/Odometry``, ``plansys2_msgs/srv/GetPlan_Request``,
    ``nav2_msgs/action/NavigateToPose_SendGoal_Request``. The class has ROS 2's DDS
    type name (``typename``, e.g. ``nav_msgs::msg::dds_::Odometry_``), one dataclass
    field per ``.msg`` field in order, zero defaults (nested messages default to their
    own zero value), and writes XCDR1 when its writer asks for it
    (``Policy.DataRepresentation(use_cdrv0_representation=True)``), which is what
    ROS 2 nodes on Cyclone DDS read. Use it with ``cyclonedds.topic.Topic`` on
    ``rt/<topic>``. Raises :class:`~plansys_bridge.interfaces.definitions.InterfaceError`
    for an unknown name.
    """
    with _lock:
        cls = _classes.get(name)
        if cls is None:
            dds_type_name(name)  # a malformed name is its own error
            cls = _make(name, ())
        return cls


def ros2_constants(name: str) -> dict[str, Any]:
    """The constants a ROS 2 message declares (``{"REQUEST": 1, ...}``)."""
    defs = ros2_fielddefs()
    if name not in defs:
        raise InterfaceError(f"unknown ROS 2 message type {name!r}")
    return {cname: value for cname, _ctype, value in defs[name][0]}


def _make(name: str, chain: tuple[str, ...]) -> type[IdlStruct]:
    defs = ros2_fielddefs()
    if name not in defs:
        where = f" (used by {chain[-1]})" if chain else ""
        raise InterfaceError(f"unknown ROS 2 message type {name!r}{where}")
    if name in chain:  # pragma: no cover - .msg files cannot nest a type in itself
        raise InterfaceError(f"ROS 2 type {name!r} contains itself")
    annotations: dict[str, Any] = {}
    namespace_defaults: dict[str, Any] = {}
    for field_name, desc in defs[name][1]:
        annotation, default = _field(desc, (*chain, name))
        annotations[field_name] = annotation
        namespace_defaults[field_name] = default
    class_name = name.rsplit("/", 1)[1] + "_"
    bases = (IdlStruct,)
    namespace: Any = IdlMeta.__prepare__(class_name, bases, typename=dds_type_name(name))
    namespace["__annotations__"].update(annotations)
    namespace.update(namespace_defaults)
    namespace["__module__"] = __name__
    namespace["__doc__"] = f"ROS 2 ``{name}`` as a DDS type (generated from its .msg text)."
    made: Any = IdlMeta(class_name, bases, namespace)
    cls: type[IdlStruct] = dataclasses.dataclass(made)
    _classes[name] = cls
    return cls


def _field(desc: tuple[Any, Any], chain: tuple[str, ...]) -> tuple[Any, Any]:
    """The IDL annotation and the dataclass default of one rosbags field description."""
    kind, detail = desc
    if kind == Nodetype.BASE:
        base, bound = detail
        if base not in _BASE:
            raise InterfaceError(f"{chain[-1]}: unsupported field type {base!r}")
        if base == "string" and bound:
            return _BOUNDED_STR[bound], ""
        return _BASE[base], _ZERO.get(base, 0)
    if kind == Nodetype.NAME:
        nested = _classes.get(detail) or _make(detail, chain)
        return nested, dataclasses.field(default_factory=nested)
    element, default = _field(detail[0], chain)
    size = detail[1]
    if kind == Nodetype.ARRAY:
        factory = _element_factory(default)
        return _ARRAY[element, size], dataclasses.field(
            default_factory=lambda: [factory() for _ in range(size)]
        )
    annotation = _SEQUENCE[element, size] if size else _SEQUENCE[element]
    return annotation, dataclasses.field(default_factory=list)


def _element_factory(default: Any) -> Any:
    if isinstance(default, dataclasses.Field):
        return default.default_factory
    return lambda: default
