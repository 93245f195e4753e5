"""Which of its own messages a distributed transport must also deliver in its process.

A transport delivers what it publishes to its own subscribers as well as sending it
out. With a hub on top, each topic has one subscriber, the hub's router, which hands
a message on to the local subscribers it concerns
(:mod:`~plansys_bridge.hub.routing`). In an auction over DDS nearly every message is
for another process (every RESPONSE for the executor, every REJECT for one
performer), and delivering it at home only to find that nobody there wants it was a
loop callback, a routing and a dispatch per message. A subscriber that can say which
messages it wants (``wants(msg)``) lets the transport skip that; a subscriber that
cannot wants everything.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from plansys_bridge.hub.transport import Subscription

__all__ = ["LocalInterest", "Wants"]

Wants = Callable[[object], bool]


class LocalInterest:
    """Per topic, what the transport's own subscribers want of its messages.

    The subscriptions are the transport's own, handed back as they are (so a hub's
    router can rewire them: :func:`~plansys_bridge.hub.transport.redirect`); one that
    was closed is noticed the next time its topic is asked about (a subscription has
    a ``closed`` flag), and leaves the table then.
    """

    def __init__(self) -> None:
        self._entries: dict[str, list[tuple[Subscription, Wants | None]]] = {}
        self._filters: dict[str, tuple[tuple[Wants, ...] | None, tuple[Any, ...]]] = {}
        """Per topic with subscribers: their filters (None: some subscriber wants every
        message), and the subscriptions they hold for."""

    def track(self, topic: str, sub: Subscription, wants: Wants | None) -> Subscription:
        """Remember ``sub`` (``wants`` None: it wants everything) until it is closed."""
        self._entries.setdefault(topic, []).append((sub, wants))
        self._update(topic)
        return sub

    def wanted(self, topic: str, msg: object) -> bool:
        """Does some local subscriber of ``topic`` want ``msg``?"""
        entry = self._filters.get(topic)
        if entry is None:
            return True
        filters, subs = entry
        if len(subs) != 1 or subs[0].closed:  # the usual case, one open router, inlined
            filters = self._current(topic)
        if filters is None:
            return True
        if len(filters) == 1:  # the hub's router: the usual case
            return filters[0](msg)
        return any(wants(msg) for wants in filters)

    def wants(self, topic: str) -> Wants | None:
        """What tells whether a message of ``topic`` is wanted (None: every one is):
        asked once for a batch, then of each message without a call of the table's."""
        filters = self._current(topic)
        if filters is None:
            return None
        if len(filters) == 1:
            return filters[0]
        return lambda msg: any(wants(msg) for wants in filters)

    def _current(self, topic: str) -> tuple[Wants, ...] | None:
        """The filters of ``topic``'s open subscriptions (None: nobody to ask, or
        somebody wants everything)."""
        entry = self._filters.get(topic)
        if entry is None:
            return None
        filters, subs = entry
        for sub in subs:
            if sub.closed:
                self._update(topic)
                return self._current(topic)
        return filters

    def _update(self, topic: str) -> None:
        entries = [e for e in self._entries.get(topic, ()) if not getattr(e[0], "closed", False)]
        if not entries:
            self._entries.pop(topic, None)
            self._filters.pop(topic, None)
            return
        self._entries[topic] = entries
        wants = [w for _s, w in entries]
        filters = None if None in wants else tuple(w for w in wants if w)
        self._filters[topic] = (filters, tuple(s for s, _w in entries))
