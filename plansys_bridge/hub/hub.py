"""The hub: one transport plus the clock everybody stamps messages with."""

from __future__ import annotations

from collections.abc import Callable

from plansys_bridge.clock import Clock, WallClock
from plansys_bridge.hub.transport import InProcessTransport, Subscription, Transport

__all__ = ["Hub"]


class Hub:
    """What executors and performers hold: ``publish``, ``subscribe`` and the ``clock``.

    A thin wrapper so that code never depends on which transport carries the
    messages; swapping the in-process transport for DDS changes nothing else.
    """

    def __init__(self, transport: Transport | None = None, clock: Clock | None = None) -> None:
        self.transport: Transport = transport if transport is not None else InProcessTransport()
        self.clock: Clock = clock if clock is not None else WallClock()

    def publish(self, topic: str, msg: object) -> None:
        self.transport.publish(topic, msg)

    def subscribe(self, topic: str, callback: Callable[[object], None]) -> Subscription:
        return self.transport.subscribe(topic, callback)

    async def start(self) -> None:
        await self.transport.start()

    async def close(self) -> None:
        await self.transport.close()

    def now(self) -> float:
        """The clock's mission time, for stamps."""
        return self.clock.now()

    def __repr__(self) -> str:
        return f"Hub({type(self.transport).__name__}, {self.clock!r})"
