"""Bridge files: which topics cross between ROS 1 and ROS 2, in which direction, how.

::

    ros1: {master_uri: http://127.0.0.1:11311}    # default $ROS_MASTER_URI
    ros2: {domain_id: 42}                          # Cyclone DDS on loopback
    topics:
      - {topic: /chatter, type: std_msgs/msg/String, from: ros1}
      - {topic: /cmd, type: std_msgs/msg/String, from: ros2}
      - topic: /mobile_base_controller/odom
        to: /odom                                  # the name on the other side
        type: nav_msgs/msg/Odometry
        from: ros1
        rate: 20                                   # forward at most 20 messages/s
        qos: {reliability: best_effort, durability: volatile, depth: 5}

``qos`` is the ROS 2 side's (default: reliable, volatile, depth 10, as ROS 2's
default profile); ``durability: transient_local`` also latches the ROS 1 side.
A mission file may carry the same mapping under ``bridge:``. Every error names the
file and key.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.dds_config import MAX_DOMAIN_ID
from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.master import check_uri
from plansys_bridge.ros1.node import DEFAULT_MASTER_URI, resolve_topic
from plansys_bridge.ros1.types import store_name

__all__ = ["BridgeConfig", "Qos", "TopicRoute", "load_bridge_config", "parse_bridge_config"]

_TOP_KEYS = ("ros1", "ros2", "topics")
_TOPIC_KEYS = ("topic", "to", "type", "from", "rate", "qos")
_QOS_KEYS = ("reliability", "durability", "depth")


@dataclass(frozen=True)
class Qos:
    reliability: Literal["reliable", "best_effort"] = "reliable"
    durability: Literal["volatile", "transient_local"] = "volatile"
    depth: int = 10


@dataclass(frozen=True)
class TopicRoute:
    """One topic crossing in one direction."""

    source: str
    """The topic name on the side it comes from."""
    target: str
    """The topic name on the other side (``to``, default the same name)."""
    type_name: str
    """ROS 2 form: ``nav_msgs/msg/Odometry``."""
    direction: Literal["ros1", "ros2"]
    """Where messages come from."""
    rate: float | None
    qos: Qos
    key: str


@dataclass(frozen=True)
class BridgeConfig:
    master_uri: str
    domain_id: int
    routes: tuple[TopicRoute, ...]
    source: str = ""


def _err(message: str, key: str, source: str) -> ConfigError:
    return ConfigError(message, key=key, file=source or None)


def _keys(
    value: object, allowed: tuple[str, ...], key: str, source: str, hint: str
) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise _err(hint, key, source)
    for name in value:
        if name not in allowed:
            raise _err(
                f"unknown key (allowed: {', '.join(allowed)})", f"{key}.{name}".lstrip("."), source
            )
    return value


def parse_bridge_config(data: object, *, source: str = "", key: str = "") -> BridgeConfig:
    """Check a bridge mapping (a bridge file, or a mission's ``bridge:``)."""
    pre = f"{key}." if key else ""
    top = _keys(data, _TOP_KEYS, key, source, "a bridge needs ros1, ros2 and topics")
    ros1 = _keys(top.get("ros1") or {}, ("master_uri",), f"{pre}ros1", source, "must be a mapping")
    master = ros1.get("master_uri") or os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI
    try:
        master_uri = check_uri(str(master))
    except Ros1Error as exc:
        raise _err(str(exc), f"{pre}ros1.master_uri", source) from exc
    ros2 = _keys(top.get("ros2") or {}, ("domain_id",), f"{pre}ros2", source, "must be a mapping")
    domain_id = ros2.get("domain_id", 0)
    if (
        isinstance(domain_id, bool)
        or not isinstance(domain_id, int)
        or not 0 <= domain_id <= MAX_DOMAIN_ID
    ):
        raise _err(
            f"must be an integer within 0..{MAX_DOMAIN_ID}, got {domain_id!r}",
            f"{pre}ros2.domain_id",
            source,
        )
    topics = top.get("topics")
    if not isinstance(topics, list) or not topics:
        raise _err("must list the topics to bridge", f"{pre}topics", source)
    routes = [_route(entry, f"{pre}topics[{i}]", source) for i, entry in enumerate(topics)]
    seen: dict[tuple[str, str], str] = {}
    for route in routes:
        ident = (route.direction, route.source)
        if ident in seen:
            raise _err(
                f"{route.source} from {route.direction} is already bridged by {seen[ident]}",
                route.key,
                source,
            )
        seen[ident] = route.key
    for route in routes:
        back = seen.get(("ros2" if route.direction == "ros1" else "ros1", route.target))
        if back is not None:
            raise _err(
                f"{route.target} would go round in a loop: {back} bridges it back",
                route.key,
                source,
            )
    return BridgeConfig(master_uri, domain_id, tuple(routes), source)


def _route(entry: object, key: str, source: str) -> TopicRoute:
    spec = _keys(entry, _TOPIC_KEYS, key, source, "must be {topic, type, from: ros1|ros2}")
    for needed in ("topic", "type", "from"):
        if needed not in spec:
            raise _err(f"missing {needed!r}", key, source)
    try:
        topic = resolve_topic(str(spec["topic"]))
        target = resolve_topic(str(spec.get("to", topic)))
    except Ros1Error as exc:
        raise _err(str(exc), f"{key}.topic", source) from exc
    type_text = spec["type"]
    if not isinstance(type_text, str) or type_text.count("/") != 2 or "/msg/" not in type_text:
        raise _err(
            f"name the type in ROS 2 form (pkg/msg/Type), got {type_text!r}", f"{key}.type", source
        )
    direction = spec["from"]
    if direction not in ("ros1", "ros2"):
        raise _err(f"must be ros1 or ros2, got {direction!r}", f"{key}.from", source)
    rate = spec.get("rate")
    if rate is not None and (
        isinstance(rate, bool)
        or not isinstance(rate, int | float)
        or not (rate > 0 and math.isfinite(rate))
    ):
        raise _err(f"must be messages per second > 0, got {rate!r}", f"{key}.rate", source)
    qos_spec = _keys(spec.get("qos") or {}, _QOS_KEYS, f"{key}.qos", source, "must be a mapping")
    reliability = qos_spec.get("reliability", "reliable")
    if reliability not in ("reliable", "best_effort"):
        raise _err(
            f"must be reliable or best_effort, got {reliability!r}",
            f"{key}.qos.reliability",
            source,
        )
    durability = qos_spec.get("durability", "volatile")
    if durability not in ("volatile", "transient_local"):
        raise _err(
            f"must be volatile or transient_local, got {durability!r}",
            f"{key}.qos.durability",
            source,
        )
    depth = qos_spec.get("depth", 10)
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise _err(f"must be an integer >= 1, got {depth!r}", f"{key}.qos.depth", source)
    return TopicRoute(
        source=topic,
        target=target,
        type_name=store_name(type_text),
        direction=direction,
        rate=float(rate) if rate is not None else None,
        qos=Qos(reliability, durability, depth),
        key=key,
    )


def load_bridge_config(path: str | Path) -> BridgeConfig:
    """Read and check a bridge file, or a mission file's ``bridge:`` section.

    ConfigError naming file:line:col or the key.
    """
    from plansys_bridge.yaml_files import load_yaml_file

    data = load_yaml_file(path, "bridge file")
    if isinstance(data, Mapping) and "topics" not in data and "domain" in data:
        if data.get("bridge") is None:
            raise _err("this mission file has no bridge: section", "bridge", str(path))
        return parse_bridge_config(data["bridge"], source=str(path), key="bridge")
    return parse_bridge_config(data, source=str(path))
