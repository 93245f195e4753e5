"""The hub: one transport plus the clock everybody stamps messages with."""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Sequence
from typing import TYPE_CHECKING

from plansys_bridge.clock import Clock, WallClock
from plansys_bridge.hub.client_table import ClientTable
from plansys_bridge.hub.liveness import LivenessTable
from plansys_bridge.hub.messages import Topics
from plansys_bridge.hub.routing import TopicRouter
from plansys_bridge.hub.transport import InProcessTransport, Subscription, Transport

__all__ = ["Hub"]


class Hub:
    """What executors and performers hold: ``publish``, ``subscribe`` and the ``clock``.

    A thin wrapper so that code never depends on which transport carries the
    messages; swapping the in-process transport for DDS changes nothing else. The hub
    takes one transport subscription per topic and routes each message to the local
    subscribers it concerns (:mod:`plansys_bridge.hub.routing`); heartbeats feed one
    :class:`~plansys_bridge.hub.liveness.LivenessTable`.
    """

    def __init__(self, transport: Transport | None = None, clock: Clock | None = None) -> None:
        self.transport: Transport = transport if transport is not None else InProcessTransport()
        self.clock: Clock = clock if clock is not None else WallClock()
        self._routers: dict[str, TopicRouter] = {}
        self.publish: Callable[[str, object], None] = self.transport.publish
        """``publish(topic, msg)``: the transport's own method, bound once, so a message
        costs no call of the hub's (an action's auction publishes about ten)."""
        self.publish_many: Callable[[str, Sequence[object]], None] = getattr(
            self.transport, "publish_many", self._publish_each
        )
        """``publish_many(topic, msgs)``: ``publish`` for each, in one call where the
        transport can (the REJECTs that end an auction)."""
        self.has_audience: Callable[[str], bool] = getattr(self.transport, "has_audience", _anybody)
        """``has_audience(topic)``: would a message published on ``topic`` now reach
        anybody? What only informs (the plan's DOT graph, its execution info) is not
        worked out for nobody, as a ROS node asks its publisher's subscription count
        first. A transport that cannot tell (DDS: readers in other processes) does not
        define it, and the answer is then always yes; the in-process transport answers
        from its subscribers, so a subscriber made later gets the next message."""

    def _publish_each(self, topic: str, messages: Sequence[object]) -> None:
        for msg in messages:
            self.publish(topic, msg)

    def subscribe(
        self,
        topic: str,
        callback: Callable[[object], None],
        *,
        keys: Iterable[Hashable] | None = None,
    ) -> Subscription:
        """Call ``callback(msg)`` on the loop for messages of ``topic``.

        Without ``keys``: every message. With ``keys`` (see
        :func:`~plansys_bridge.hub.routing.performer_keys` and
        :func:`~plansys_bridge.hub.routing.client_keys`): only the messages routed to
        one of them, plus any message the topic's router cannot place.
        """
        router = self._routers.get(topic)
        if router is None:
            router = self._router(topic)
        return router.add(callback, keys)

    def _router(self, topic: str) -> TopicRouter:
        """The router of ``topic``, subscribed to the transport on first use."""
        router = self._routers.get(topic)
        if router is None:
            router = TopicRouter(topic)
            # A transport that can skip delivering its own messages nobody here wants
            # (DDS) is told what the router wants.
            subscribe_wanting = getattr(self.transport, "subscribe_wanting", None)
            router.transport_subscription = (
                subscribe_wanting(topic, router.dispatch, router.wants)
                if subscribe_wanting is not None
                else self.transport.subscribe(topic, router.dispatch)
            )
            self._routers[topic] = router
        return router

    liveness: LivenessTable
    """The heartbeat table of this hub, made and subscribed on first use (by
    ``__getattr__``); from then on a plain attribute, read without a call (every
    auction client reads it, once per action)."""

    clients: ClientTable
    """The auction clients of ``actions_hub`` (:mod:`~plansys_bridge.hub.client_table`),
    its router made on first use (by ``__getattr__``); then a plain attribute."""

    if not TYPE_CHECKING:  # (hidden from mypy: no other name may pass for an attribute)

        def __getattr__(self, name: str) -> LivenessTable | ClientTable:
            if name == "clients" and "_routers" in self.__dict__:
                clients = self.clients = self._router(Topics.ACTIONS_HUB).clients
                return clients
            if name != "liveness" or "_routers" not in self.__dict__:
                raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
            table = LivenessTable()
            # A change of state's statuses (one per action served) in one call
            self._router(Topics.PERFORMERS_STATUS).add(table.on_status, None, table.on_statuses)
            self.liveness = table
            return table

    async def start(self) -> None:
        await self.transport.start()

    async def close(self) -> None:
        for router in self._routers.values():
            router.close()
        self._routers.clear()
        self.__dict__.pop("liveness", None)  # a new table on next use
        self.__dict__.pop("clients", None)
        await self.transport.close()

    def now(self) -> float:
        """The clock's mission time, for stamps."""
        return self.clock.now()

    def __repr__(self) -> str:
        return f"Hub({type(self.transport).__name__}, {self.clock!r})"


def _anybody(topic: str) -> bool:
    """``has_audience`` of a transport that cannot tell: somebody may listen."""
    return True
