"""Routing inside a hub: a message reaches only the subscribers it concerns.

On ``actions_hub`` every message of an auction is for a few parties: a REQUEST for the
performers offering that action, a RESPONSE/FEEDBACK/FINISH for the client that asked,
a CONFIRM/REJECT/CANCEL for one node. Broadcasting each to every subscriber made one
auction among N bidders cost N x N deliveries; routing by key makes it N.

A subscription with ``keys`` gets the messages whose route key is one of them; one
without keys gets every message of the topic (recorders, monitors, a foreign client).
A message whose topic has no router, or that the router cannot place (a type it does
not know), goes to every subscriber, keyed or not: routing never loses a message a
subscriber could want.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Hashable, Iterable
from heapq import merge
from itertools import count
from typing import Any

from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.hub.transport import Subscription, report_subscriber_error

__all__ = [
    "TopicRouter",
    "client_keys",
    "performer_keys",
    "route_key",
]

Callback = Callable[[object], None]

_TO_CLIENT = frozenset({ExecutionType.RESPONSE, ExecutionType.FEEDBACK, ExecutionType.FINISH})
# Reading an enum member off its class costs about 0.3 us on Python 3.11, more than
# the rest of routing a message: the members used per message are read once here.
_REQUEST = ExecutionType.REQUEST


def _action_route(msg: object) -> Hashable | None:
    if not isinstance(msg, ActionExecution):
        return None
    kind = msg.type
    if kind is _REQUEST:
        return ("action", msg.action)
    if kind in _TO_CLIENT:
        if msg.request_id:
            return ("request", msg.request_id)
        return ("text", msg.action, tuple(msg.arguments))
    return ("node", msg.node_id)


_ROUTERS: dict[str, Callable[[object], Hashable | None]] = {Topics.ACTIONS_HUB: _action_route}


def route_key(topic: str, msg: object) -> Hashable | None:
    """The key ``msg`` is routed by on ``topic`` (None: deliver to everybody)."""
    router = _ROUTERS.get(topic)
    return router(msg) if router is not None else None


def performer_keys(node_name: str, actions: Iterable[str]) -> list[Hashable]:
    """What a performer hears on ``actions_hub``: REQUESTs for its actions, and the
    CONFIRM/REJECT/CANCEL messages naming it."""
    return [*(("action", a) for a in actions), ("node", node_name)]


def client_keys(request_id: str, action: str, arguments: Iterable[str]) -> list[Hashable]:
    """What an auction client hears: answers carrying its request id, and answers
    without one that name its action text (PlanSys2 matches on the text alone)."""
    keys: list[Hashable] = [("text", action, tuple(arguments))]
    if request_id:
        keys.append(("request", request_id))
    return keys


class _RoutedSubscription:
    __slots__ = ("callback", "closed", "keys", "order", "router")

    def __init__(
        self, router: TopicRouter, callback: Callback, keys: tuple[Hashable, ...] | None, order: int
    ) -> None:
        self.router = router
        self.callback = callback
        self.keys = keys
        self.order = order
        self.closed = False

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self.router._remove(self)

    def __lt__(self, other: _RoutedSubscription) -> bool:
        return self.order < other.order

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"<Subscription {self.router.topic!r} keys={self.keys} {state}>"


class TopicRouter:
    """The subscribers of one topic in one hub, fed by one transport subscription.

    Lists are copied on write, so a delivery in progress keeps the subscribers it
    started with; a subscription closed meanwhile is skipped (closing stops delivery
    even of messages already queued). Subscribers are called in subscription order.
    """

    def __init__(self, topic: str) -> None:
        self.topic = topic
        self._everyone: list[_RoutedSubscription] = []
        self._keyed: dict[Hashable, list[_RoutedSubscription]] = {}
        self._all_keyed: list[_RoutedSubscription] = []
        self._router = _ROUTERS.get(topic)
        self._order = count()
        self.transport_subscription: Subscription | None = None

    def add(self, callback: Callback, keys: Iterable[Hashable] | None) -> Subscription:
        key_tuple = None if keys is None else tuple(dict.fromkeys(keys))
        sub = _RoutedSubscription(self, callback, key_tuple, next(self._order))
        if key_tuple is None or self._router is None:
            self._everyone = [*self._everyone, sub]
        else:
            for key in key_tuple:
                self._keyed[key] = [*self._keyed.get(key, ()), sub]
            self._all_keyed = [*self._all_keyed, sub]
        return sub

    def _remove(self, sub: _RoutedSubscription) -> None:
        if sub in self._everyone:
            self._everyone = [s for s in self._everyone if s is not sub]
            return
        for key in sub.keys or ():
            remaining = [s for s in self._keyed.get(key, ()) if s is not sub]
            if remaining:
                self._keyed[key] = remaining
            else:
                self._keyed.pop(key, None)
        self._all_keyed = [s for s in self._all_keyed if s is not sub]

    def __len__(self) -> int:
        return len(self._everyone) + len(self._all_keyed)

    def wants(self, msg: object) -> bool:
        """Would :meth:`dispatch` deliver ``msg`` to anybody now?"""
        if self._everyone:
            return True
        key = self._router(msg) if self._router is not None else None
        if key is None:
            return bool(self._all_keyed)
        return key in self._keyed

    def dispatch(self, msg: object) -> None:
        """Deliver ``msg`` (called by the transport on the loop)."""
        everyone = self._everyone
        key = self._router(msg) if self._router is not None else None
        targets: Iterable[_RoutedSubscription]
        if key is None:
            targets = merge(everyone, self._all_keyed) if self._all_keyed else everyone
        else:
            keyed = self._keyed.get(key, ())
            if not keyed:
                targets = everyone
            elif not everyone:
                targets = keyed
            else:
                targets = merge(everyone, keyed)
        for sub in targets:
            if sub.closed:
                continue
            try:
                sub.callback(msg)
            except Exception as exc:
                report_subscriber_error(_running_loop(), self.topic, exc)

    def close(self) -> None:
        for sub in (*self._everyone, *self._all_keyed):
            sub.closed = True
        self._everyone, self._keyed, self._all_keyed = [], {}, []
        if self.transport_subscription is not None:
            self.transport_subscription.close()


def _running_loop() -> Any:
    try:
        return asyncio.get_running_loop()
    except RuntimeError:  # pragma: no cover - delivery always runs on a loop
        return None
