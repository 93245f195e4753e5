"""Performer kinds are plugins found through the ``plansys_bridge.performers`` entry points.

A mission names a performer ``kind`` (``simulated``, ``mavlink``, ``can``, ``rosbag``,
or one a third-party package registers); the class is imported only when a mission
asks for it, so a missing optional dependency (pymavlink for ``mavlink``) costs
nothing until then and is reported as one clear error saying which extra to install
(:class:`~plansys_bridge.plugins.PluginRegistry`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

from plansys_bridge.errors import AdapterError, ConfigError, PlansysBridgeError, PluginError
from plansys_bridge.performers.base import ActionPerformer, PerformerContext, arguments_match
from plansys_bridge.plugins import GROUPS, PluginRegistry

__all__ = [
    "ENTRY_POINT_GROUP",
    "PERFORMERS",
    "available_performer_kinds",
    "load_performer_kind",
    "performers_from_config",
    "start_performers",
    "unserved_actions",
]

ENTRY_POINT_GROUP = GROUPS["performers"]

PERFORMERS: PluginRegistry[ActionPerformer] = PluginRegistry(
    ENTRY_POINT_GROUP,
    ActionPerformer,
    "performer kind",
    builtin={
        "simulated": "plansys_bridge.performers.simulated:SimulatedPerformer",
        "bt": "plansys_bridge.performers.bt.performer:BTActionPerformer",
        "mavlink": "plansys_bridge_adapters.mavlink.performer:MavlinkPerformer",
        "mavlink_replay": "plansys_bridge_adapters.mavlink.replay:MavlinkReplayPerformer",
        "can": "plansys_bridge_adapters.can.performer:CanBasePerformer",
        "rosbag": "plansys_bridge_adapters.rosbag.performer:BagNavigationPerformer",
        "ros2_nav2": "plansys_bridge_adapters.ros2_nav2.performer:Nav2Performer",
        "ros1_move_base": "plansys_bridge_adapters.ros1.performer:MoveBasePerformer",
    },
)
"""The performer kinds installed (entry-point group ``plansys_bridge.performers``)."""


def available_performer_kinds() -> list[str]:
    """Names of the performer kinds installed (importable or not)."""
    return sorted(PERFORMERS.names())


def load_performer_kind(kind: str) -> type[ActionPerformer]:
    """The performer class registered as ``kind``; PluginError if unknown or not importable."""
    return PERFORMERS.load(kind)


async def start_performers(
    performers: Sequence[ActionPerformer], say: Callable[[str], None] | None = None
) -> list[ActionPerformer]:
    """Start each performer in turn, saying what it connects to while it does.

    A ``setup()`` that raises (a refused connection, a missing device) is one
    AdapterError naming the performer and the cause, not a traceback; the performers
    started before it are stopped first, so nothing is left running.
    """
    started: list[ActionPerformer] = []
    for performer in performers:
        target = performer.connects_to()
        if target and say is not None:
            say(f"{performer.node_name}: connecting to {target} ...")
        try:
            await performer.start()
        except Exception as exc:
            for other in reversed(started):
                with contextlib.suppress(Exception):
                    await other.stop()
            cause = str(exc) if isinstance(exc, PlansysBridgeError) else _describe(exc)
            raise AdapterError(
                f"performer {performer.node_name!r} could not start: {cause}"
            ) from exc
        started.append(performer)
    return started


def _describe(exc: BaseException) -> str:
    """``ConnectionRefusedError: [Errno 111] Connection refused`` style, one line."""
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def unserved_actions(
    calls: Iterable[tuple[str, Sequence[str]]], performers: Sequence[ActionPerformer]
) -> list[str]:
    """The action calls (``(move r1 a b)``) that no performer offers, by name and
    specialised arguments, in plan order: the auction for them could only time out."""
    missing: list[str] = []
    for name, arguments in calls:
        offered = any(
            name in p.actions and arguments_match(p.actions[name], arguments) for p in performers
        )
        text = f"({' '.join([name, *arguments])})"
        if not offered and text not in missing:
            missing.append(text)
    return missing


def performers_from_config(
    entries: Sequence[Mapping[str, Any]], context: PerformerContext, *, key: str = "performers"
) -> list[ActionPerformer]:
    """Build every performer of a mission's ``performers:`` list, errors naming the entry."""
    performers: list[ActionPerformer] = []
    names: dict[str, str] = {}
    for i, entry in enumerate(entries):
        where = f"{key}[{i}]"
        if not isinstance(entry, Mapping):
            raise ConfigError("a performer entry must be a mapping", key=where)
        kind = entry.get("kind")
        if not isinstance(kind, str) or not kind:
            raise ConfigError("missing performer kind", key=f"{where}.kind")
        try:
            cls = load_performer_kind(kind)
        except PluginError as exc:
            raise ConfigError(str(exc), key=f"{where}.kind") from exc
        for performer in cls.from_config(entry, context, key=where):
            if performer.node_name in names:
                raise ConfigError(
                    f"performer name {performer.node_name!r} already used by "
                    f"{names[performer.node_name]}",
                    key=f"{where}.name",
                )
            names[performer.node_name] = where
            performers.append(performer)
    return performers
