"""rosbags typestore entries and MCAP schemas generated from the vendored ROS 2 texts.

:func:`ros2_typestore` is the one registry of ROS 2 message layouts in the project:
the recorder writes bags with it (rosbags embeds each topic's ``ros2msg`` schema,
:func:`mcap_schema`, in the MCAP file), replays read with it, and the Cyclone DDS
types of :mod:`plansys_bridge.interfaces.dds` are generated from its field
definitions. It starts from rosbags' empty store and holds exactly the vendored
packages, so a layout is whatever upstream's text says and nothing else.

rosbags is an optional dependency (the ``rosbag`` and ``dds`` extras); a missing
install is one :class:`~plansys_bridge.errors.PluginError` naming the extra.
"""

from __future__ import annotations

from functools import cache
from typing import Any, cast

from plansys_bridge.errors import PluginError
from plansys_bridge.interfaces.definitions import InterfaceError, ros2_definitions

try:
    from rosbags.typesys import Stores, TypesysError, get_types_from_msg, get_typestore
    from rosbags.typesys.base import Nodetype
    from rosbags.typesys.store import Typestore
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise PluginError(
        "ROS 2 message types need rosbags: pip install 'plansys-bridge[rosbag]'"
    ) from exc

__all__ = [
    "EMPTY_MEMBER",
    "FieldDefs",
    "Nodetype",
    "mcap_schema",
    "ros2_fielddefs",
    "ros2_typestore",
]

FieldDefs = dict[str, tuple[list[tuple[str, str, Any]], list[tuple[str, Any]]]]
"""rosbags' parsed form: type name -> (constants, fields)."""

EMPTY_MEMBER = "structure_needs_at_least_one_member"


def _parse(name: str, text: str) -> tuple[list[Any], list[Any]]:
    """Parse one definition; relative names resolve to ``pkg/msg/...`` as in rosidl.

    rosbags resolves a relative name against the definition's own namespace, which
    for ``pkg/srv/X_Request`` would be ``pkg/srv/``; parsing under a ``pkg/msg/``
    name gives rosidl's meaning.
    """
    pkg = name.split("/", 1)[0]
    probe = f"{pkg}/msg/{name.rsplit('/', 1)[1]}"
    constants, fields = get_types_from_msg(text, probe)[probe]
    if not fields:
        # rosidl gives an empty message one uint8 member (IDL has no empty structs).
        fields = [(EMPTY_MEMBER, (Nodetype.BASE, ("uint8", 0)))]
    return constants, fields


@cache
def ros2_fielddefs() -> FieldDefs:
    """The parsed field definitions of every vendored ROS 2 message, by type name."""
    types: FieldDefs = {}
    for name, definition in ros2_definitions().items():
        try:
            types[name] = _parse(name, definition.text)
        except TypesysError as exc:
            raise InterfaceError(f"{definition.source}: {name}: {exc}") from exc
    return types


@cache
def ros2_typestore() -> Typestore:
    """A rosbags typestore holding exactly the vendored ROS 2 messages (built once).

    Callers may register further types of their own (an adapter's custom messages);
    the vendored entries are never replaced, rosbags refuses a different definition
    under a registered name.
    """
    store = get_typestore(Stores.EMPTY)
    try:
        store.register(cast(Any, ros2_fielddefs()))
    except TypesysError as exc:
        raise InterfaceError(f"vendored ROS 2 interfaces: {exc}") from exc
    return store


def mcap_schema(name: str) -> tuple[str, str]:
    """The ``(schema text, encoding)`` an MCAP file carries for the ROS 2 type ``name``.

    The text is the ``.msg`` definition followed by those of every type it uses, in
    the ``ros2msg`` format rosbag2 writes (rosbags' ``generate_msgdef``).
    """
    store = ros2_typestore()
    if name not in store.fielddefs:
        raise InterfaceError(f"unknown ROS 2 message type {name!r}")
    text, _digest = store.generate_msgdef(name, ros_version=2)
    return text, "ros2msg"
