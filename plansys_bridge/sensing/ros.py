"""ROS 1 and ROS 2 topic fields as sensing sources.

``{from: ros1, topic: /battery_state, type: sensor_msgs/msg/BatteryState, when:
"percentage < 0.25", predicate: "(battery_low r1)"}`` subscribes with the project's
own ROS 1 client (:mod:`plansys_bridge.ros1`, the one the bridge uses; ``master_uri``
or ``ROS_MASTER_URI``); ``from: ros2`` reads the topic over Cyclone DDS as a ROS 2
node does (:class:`~plansys_bridge.bridge.ros2_side.Ros2Side`, the bridge's ROS 2
side; ``domain_id``, default the mission's DDS domain or 0). Types are named in
ROS 2 form; fields are paths into the message (``pose.pose.position.x``, arrays by
index: ``cell_voltage[0]``), checked against the type's definition in the typestore
when the mission loads. ``field`` is a function rule's value (an expression).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import re
import secrets
from typing import Any, ClassVar

from pydantic import BaseModel, Field

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.plugins import PluginSettings

from .expressions import Expression, ExpressionError, parse_expression
from .source import Detach, Feed, RuleSite, SensingSource, flatten

__all__ = ["Ros1TopicSource", "Ros2TopicSource", "field_paths"]

log = logging.getLogger(__name__)

_INDEX = re.compile(r"\[\d+\]")


def field_paths(store: Any, type_name: str, prefix: str = "") -> set[str]:
    """Every field path of ``type_name`` in a rosbags typestore; array elements as ``[*]``."""
    paths: set[str] = set()
    for name, (nodetype, detail) in store.fielddefs[type_name][1]:
        path = f"{prefix}.{name}" if prefix else name
        kind = int(nodetype)
        if kind == 2:  # a nested message
            paths |= field_paths(store, detail, path)
            continue
        paths.add(path)
        if kind in (3, 4):  # array, sequence: (element, size)
            element_kind, element = detail[0]
            paths.add(f"{path}[*]")
            if int(element_kind) == 2:
                paths |= field_paths(store, element, f"{path}[*]")
    return paths


class RosTopicSettings(PluginSettings):
    topic: str
    type: str
    """The message type in ROS 2 form: ``sensor_msgs/msg/BatteryState``."""
    field: str | None = None
    """The value a function rule writes: a field path or an expression over fields."""


class Ros1Settings(RosTopicSettings):
    master_uri: str | None = None
    """Default: ``ROS_MASTER_URI``."""


class Ros2Settings(RosTopicSettings):
    domain_id: int | None = Field(None, ge=0, le=232)
    """Default: the mission's DDS domain, else 0."""


class _RosTopicSource(SensingSource):
    Settings: ClassVar[type[BaseModel]] = RosTopicSettings
    flavour: ClassVar[str] = ""

    def __init__(self, settings: BaseModel) -> None:
        super().__init__(settings)
        assert isinstance(settings, RosTopicSettings)
        self.topic = settings.topic
        self.type_name = settings.type
        self._value: Expression | None = None

    def describe(self) -> str:
        return f"{self.topic} ({self.flavour})"

    def _store(self) -> Any:
        raise NotImplementedError

    def check(self, site: RuleSite) -> frozenset[str]:
        assert isinstance(self.settings, RosTopicSettings)
        store = self._store()
        if self.type_name not in store.fielddefs:
            raise ConfigError(
                f"unknown {self.flavour} message type {self.type_name!r} (name it in ROS 2 "
                "form, e.g. sensor_msgs/msg/BatteryState)",
                key="type",
            )
        paths = field_paths(store, self.type_name)
        if self.settings.field is not None:
            try:
                self._value = parse_expression(self.settings.field)
            except ExpressionError as exc:
                raise ConfigError(str(exc), key="field") from exc
            self._check_fields(self._value, paths, "field")
        return _IndexedPaths(paths)

    def _check_fields(self, expr: Expression, paths: set[str], key: str) -> None:
        for name in sorted(expr.fields):
            if _INDEX.sub("[*]", name) not in paths:
                raise ConfigError(f"{self.type_name} has no field {name!r}", key=key)

    def value(self) -> Expression | None:
        return self._value


class _IndexedPaths(frozenset[str]):
    """Field paths where ``[*]`` stands for any index (``cell_voltage[3]`` is in it)."""

    def __contains__(self, name: object) -> bool:
        if not isinstance(name, str):
            return False
        return frozenset.__contains__(self, _INDEX.sub("[*]", name))

    def __rsub__(self, other: Any) -> Any:
        return frozenset(x for x in other if x not in self)


def _sample(msg: Any) -> dict[str, Any]:
    return flatten(msg)


class Ros1TopicSource(_RosTopicSource):
    """A ROS 1 topic, through the project's ROS 1 client (no rospy)."""

    Settings: ClassVar[type[BaseModel]] = Ros1Settings
    flavour: ClassVar[str] = "ROS 1"

    def _store(self) -> Any:
        from plansys_bridge.ros1.types import Ros1Types

        return Ros1Types.default().store

    def attach(self, performer: Any, feed: Feed) -> Detach:
        from plansys_bridge.ros1.node import Node

        assert isinstance(self.settings, Ros1Settings)
        uri = self.settings.master_uri
        topic, type_name = self.topic, self.type_name

        async def run() -> None:
            name = f"plansys_sensing_{secrets.token_hex(3)}"
            async with Node(name, master_uri=uri) as node:
                await node.subscribe(topic, type_name, lambda msg: feed(_sample(msg)))
                await asyncio.Event().wait()

        return _background(run(), f"ros1 sensing {topic}")


class Ros2TopicSource(_RosTopicSource):
    """A ROS 2 topic over Cyclone DDS, with ROS 2's names and types."""

    Settings: ClassVar[type[BaseModel]] = Ros2Settings
    flavour: ClassVar[str] = "ROS 2"

    def __init__(self, settings: BaseModel) -> None:
        super().__init__(settings)
        self.domain_id = 0

    def _store(self) -> Any:
        from plansys_bridge.interfaces.typestore import ros2_typestore

        return ros2_typestore()

    def check(self, site: RuleSite) -> frozenset[str]:
        assert isinstance(self.settings, Ros2Settings)
        transport = getattr(site.mission, "transport", None)
        mission_domain = getattr(transport, "domain_id", 0) if transport is not None else 0
        self.domain_id = (
            self.settings.domain_id if self.settings.domain_id is not None else mission_domain
        )
        return super().check(site)

    def attach(self, performer: Any, feed: Feed) -> Detach:
        from plansys_bridge.bridge.config import Qos
        from plansys_bridge.bridge.ros2_side import Ros2Side

        side = Ros2Side(self.domain_id)
        try:
            side.reader(
                self.topic,
                self.type_name,
                Qos(),
                lambda msg: feed(_sample(msg)),
                asyncio.get_running_loop(),
            )
        except Exception as exc:
            side.close()
            raise PlansysBridgeError(f"cannot read ROS 2 topic {self.topic}: {exc}") from exc
        return side.close


def _background(coro: Any, name: str) -> Detach:
    """Run ``coro`` until detached; its failure is logged, never raised into the mission."""
    task = asyncio.get_running_loop().create_task(coro, name=name)

    def done(t: asyncio.Task[None]) -> None:
        if not t.cancelled() and t.exception() is not None:
            log.error("%s stopped: %s", name, t.exception())

    task.add_done_callback(done)

    def detach() -> None:
        with contextlib.suppress(Exception):
            task.cancel()

    return detach
