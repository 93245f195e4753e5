"""A live ROS 1 <-> ROS 2 topic bridge, in one Python process (no ros1_bridge build).

The ROS 1 side is the project's own client (:mod:`plansys_bridge.ros1`), the ROS 2
side Cyclone DDS with ROS 2's names (:mod:`.ros2_side`). Each route subscribes on
the side messages come from, converts between the ROS 1 and ROS 2 layouts
(:mod:`.convert`) and publishes on the other side, at most ``rate`` messages per
second if configured. The ROS 1 side keeps working through a master restart (it
re-registers) and a ROS 1 publisher that comes back is reconnected.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from plansys_bridge.bridge.config import BridgeConfig, TopicRoute
from plansys_bridge.bridge.convert import Converter
from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.node import Node

__all__ = ["Bridge", "RouteStats"]

log = logging.getLogger(__name__)


@dataclass
class RouteStats:
    route: TopicRoute
    forwarded: int = 0
    skipped: int = 0
    """Messages dropped by the rate limit."""
    failed: int = 0
    last: float = field(default=-float("inf"))

    def due(self) -> bool:
        """Rate limit: may a message be forwarded now?"""
        rate = self.route.rate
        now = time.monotonic()
        if rate is not None and now - self.last < 1.0 / rate:
            self.skipped += 1
            return False
        self.last = now
        return True

    def describe(self) -> str:
        r = self.route
        arrow = "ROS 1 -> ROS 2" if r.direction == "ros1" else "ROS 2 -> ROS 1"
        name = r.source if r.source == r.target else f"{r.source} -> {r.target}"
        return f"{name} [{r.type_name}] {arrow}"


class Bridge:
    """``async with Bridge(config):`` bridges ``config``'s topics until the block ends."""

    def __init__(self, config: BridgeConfig, *, name: str = "plansys_bridge_ros1_bridge") -> None:
        self.config = config
        self.name = name
        self.node: Node | None = None
        self.ros2: Any = None
        self.stats: list[RouteStats] = []

    async def start(self) -> None:
        from plansys_bridge.bridge.ros2_side import Ros2Side

        self.node = Node(self.name, master_uri=self.config.master_uri)
        await self.node.start()
        try:
            self.ros2 = Ros2Side(self.config.domain_id)
            for route in self.config.routes:
                await self._add(route)
        except BaseException:
            await self.stop()
            raise

    async def stop(self) -> None:
        if self.node is not None:
            await self.node.close()
            self.node = None
        if self.ros2 is not None:
            self.ros2.close()
            self.ros2 = None

    async def __aenter__(self) -> Bridge:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    async def _add(self, route: TopicRoute) -> None:
        node, ros2 = self.node, self.ros2
        assert node is not None and ros2 is not None
        try:
            converter = Converter(route.type_name, node.types, ros2.store)
        except Ros1Error as exc:
            raise Ros1Error(f"{route.key}: {exc}") from exc
        stats = RouteStats(route)
        self.stats.append(stats)
        if route.direction == "ros1":
            write = ros2.writer(route.target, route.type_name, route.qos)
            await node.subscribe(
                route.source, route.type_name, self._forward(stats, converter.to_ros2, write)
            )
        else:
            latch = route.qos.durability == "transient_local"
            pub = await node.advertise(route.target, route.type_name, latch=latch)
            seq = [0]

            def to_ros1(msg: Any) -> Any:
                seq[0] += 1
                return converter.to_ros1(msg, seq[0])

            ros2.reader(
                route.source,
                route.type_name,
                route.qos,
                self._forward(stats, to_ros1, pub.publish),
                asyncio.get_running_loop(),
            )

    @staticmethod
    def _forward(
        stats: RouteStats, convert: Callable[[Any], Any], send: Callable[[Any], None]
    ) -> Callable[[Any], None]:
        def forward(msg: Any) -> None:
            if not stats.due():
                return
            try:
                send(convert(msg))
            except Exception as exc:
                stats.failed += 1
                if stats.failed == 1:
                    log.warning("bridge %s: a message could not cross: %s", stats.describe(), exc)
                return
            stats.forwarded += 1

        return forward
