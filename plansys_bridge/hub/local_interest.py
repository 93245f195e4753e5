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

from plansys_bridge.hub.transport import Subscription

__all__ = ["LocalInterest", "Wants"]

Wants = Callable[[object], bool]


class _Tracked:
    """A subscription that also leaves the interest table when closed."""

    __slots__ = ("_entry", "_interest", "_sub", "_topic")

    def __init__(
        self, interest: LocalInterest, topic: str, sub: Subscription, entry: object
    ) -> None:
        self._interest = interest
        self._topic = topic
        self._sub = sub
        self._entry = entry

    def close(self) -> None:
        self._sub.close()
        self._interest._remove(self._topic, self._entry)


class LocalInterest:
    """Per topic, what the transport's own subscribers want of its messages."""

    def __init__(self) -> None:
        self._entries: dict[str, list[tuple[object, Wants | None]]] = {}
        self._filters: dict[str, tuple[Wants, ...] | None] = {}
        """None: some subscriber wants every message (or there is none to ask)."""

    def track(self, topic: str, sub: Subscription, wants: Wants | None) -> Subscription:
        """Remember ``sub`` (``wants`` None: it wants everything) until it is closed."""
        entry = object()
        self._entries.setdefault(topic, []).append((entry, wants))
        self._update(topic)
        return _Tracked(self, topic, sub, entry)

    def wanted(self, topic: str, msg: object) -> bool:
        """Does some local subscriber of ``topic`` want ``msg``?"""
        filters = self._filters.get(topic)
        if filters is None:
            return True
        if len(filters) == 1:  # the hub's router: the usual case
            return filters[0](msg)
        return any(wants(msg) for wants in filters)

    def wants(self, topic: str) -> Wants | None:
        """What tells whether a message of ``topic`` is wanted (None: every one is):
        asked once for a batch, then of each message without a call of the table's."""
        filters = self._filters.get(topic)
        if filters is None:
            return None
        if len(filters) == 1:
            return filters[0]
        return lambda msg: any(wants(msg) for wants in filters)

    def _remove(self, topic: str, entry: object) -> None:
        entries = [e for e in self._entries.get(topic, ()) if e[0] is not entry]
        self._entries[topic] = entries
        self._update(topic)

    def _update(self, topic: str) -> None:
        wants = [w for _e, w in self._entries.get(topic, ())]
        self._filters[topic] = None if not wants or None in wants else tuple(w for w in wants if w)
