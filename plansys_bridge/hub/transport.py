"""Transports carry hub messages between the executor and the performers.

A transport is a publish/subscribe bus of topics. The embedded default,
:class:`InProcessTransport`, delivers on the asyncio loop with ``call_soon``: a
publisher never runs a subscriber's code inside its own call (so a performer may
publish from its REQUEST handler without re-entering the executor), delivery keeps
publish order across all topics, and one delivery costs a single loop callback, which
keeps the executor's dispatch latency in the microseconds. A distributed transport
(DDS) implements the same protocol.
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable, Sequence
from itertools import repeat
from typing import Any, Protocol, runtime_checkable

from plansys_bridge.errors import HubError

__all__ = [
    "InProcessTransport",
    "Subscription",
    "Transport",
    "redirect",
    "report_subscriber_error",
]

log = logging.getLogger(__name__)

Callback = Callable[[object], None]

_get_running_loop = asyncio._get_running_loop
"""The running loop or None, without the exception ``get_running_loop`` raises."""


@runtime_checkable
class Subscription(Protocol):
    """A live subscription; ``close()`` stops delivery, even of messages already queued."""

    def close(self) -> None: ...


@runtime_checkable
class Transport(Protocol):
    """Publish/subscribe bus used by :class:`~plansys_bridge.hub.hub.Hub`."""

    def publish(self, topic: str, msg: object) -> None:
        """Send ``msg`` to every subscriber of ``topic``; never blocks; ordered per topic."""
        ...

    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        """Call ``callback(msg)`` on the loop for each message published on ``topic``."""
        ...

    async def start(self) -> None: ...

    async def close(self) -> None: ...


class _InProcessSubscription:
    __slots__ = ("batch", "batches", "callback", "closed", "many", "topic", "transport")

    def __init__(self, transport: InProcessTransport, topic: str, callback: Callback) -> None:
        self.transport = transport
        self.topic = topic
        self.callback = callback
        self.closed = False
        self.many: Callable[[Sequence[object]], None] | None = None
        """Takes a batch of ``publish_many`` in one call (see :func:`redirect`)."""
        self.batch: _Batches | None = None
        """How the drain hands it a batch (made when ``many`` is first set)."""
        self.batches: list[_Batches] | None = None
        """``[batch]`` while ``many`` is set: the subscribers of a batch."""

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            if self.batch is not None:
                self.batch.closed = True
            self.transport._remove(self)

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"<Subscription {self.topic!r} {state}>"


class _Batches:
    """A subscription as the drain sees it for a batch: ``callback(messages)`` is its
    ``many`` (or, once redirected without one, delivers one by one), and it is closed
    when the subscription is. Plain attributes, kept in step by :func:`redirect` and
    ``close``: the drain reads them with no call of its own."""

    __slots__ = ("callback", "closed", "sub")

    def __init__(self, sub: _InProcessSubscription) -> None:
        self.sub = sub
        self.closed = sub.closed
        self.callback: Callable[[Any], None] = self.one_by_one

    def one_by_one(self, messages: list[object]) -> None:
        """A batch queued before the subscription was redirected without ``many``."""
        sub = self.sub
        for msg in messages:
            sub.transport._deliver(sub.topic, [sub], msg)


class InProcessTransport:
    """Topics inside one process, delivered by the asyncio loop in publish order.

    The loop is the one running when the transport is started (or when the first
    message is published). Publishing from another thread is allowed: the message is
    handed to the loop with ``call_soon_threadsafe``. Publishing to a topic nobody
    listens to is not an error. A subscriber that raises does not stop delivery to the
    others; the exception goes to the loop's exception handler, which logs it.
    """

    def __init__(self) -> None:
        self._subscribers: dict[str, list[_InProcessSubscription]] = {}
        self._loop: asyncio.AbstractEventLoop | None = None
        self._loop_thread: int | None = None
        self._closed = False
        self._pending: list[tuple[str, list[_InProcessSubscription] | list[_Batches], object]] = []
        self.published = 0
        """Messages published so far (all topics), for statistics."""

    async def start(self) -> None:
        self._bind(asyncio.get_running_loop())

    async def close(self) -> None:
        self._closed = True
        for subs in self._subscribers.values():
            for sub in subs:
                sub.closed = True
                if sub.batch is not None:
                    sub.batch.closed = True
        self._subscribers.clear()

    @property
    def closed(self) -> bool:
        return self._closed

    def _bind(self, loop: asyncio.AbstractEventLoop) -> None:
        if self._loop is None or self._loop.is_closed():
            self._loop = loop
            self._loop_thread = threading.get_ident()

    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        if self._closed:
            raise HubError(f"cannot subscribe to {topic!r}: transport closed")
        sub = _InProcessSubscription(self, topic, callback)
        subs = self._subscribers.get(topic)
        # Copy-on-write: a delivery in progress keeps the list it started with.
        self._subscribers[topic] = [*subs, sub] if subs else [sub]
        return sub

    def _remove(self, sub: _InProcessSubscription) -> None:
        subs = self._subscribers.get(sub.topic)
        if subs and sub in subs:
            remaining = [s for s in subs if s is not sub]
            if remaining:
                self._subscribers[sub.topic] = remaining
            else:
                del self._subscribers[sub.topic]

    def subscriber_count(self, topic: str) -> int:
        return len(self._subscribers.get(topic, ()))

    def has_audience(self, topic: str) -> bool:
        """Would a message published on ``topic`` now reach a subscriber? (See
        :attr:`Hub.has_audience <plansys_bridge.hub.hub.Hub.has_audience>`.)"""
        return topic in self._subscribers

    def publish(self, topic: str, msg: object) -> None:
        if self._closed:
            raise HubError(f"cannot publish on {topic!r}: transport closed")
        self.published += 1
        subs = self._subscribers.get(topic)
        if not subs:
            return
        pending = self._pending
        if pending and threading.get_ident() == self._loop_thread:
            # A drain is already scheduled on the bound loop: join its batch (an
            # auction's RESPONSEs and REJECTs mostly arrive here).
            pending.append((topic, subs, msg))
            return
        loop = self._loop
        # (the loop running this is not closed: is_closed() asked only elsewhere)
        if loop is None or (loop is not _get_running_loop() and loop.is_closed()):
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError as exc:
                raise HubError(
                    f"cannot publish on {topic!r}: the transport has no event loop yet "
                    "(start it inside the running loop first)"
                ) from exc
            self._bind(loop)
        if threading.get_ident() == self._loop_thread:
            # Messages published one after another share one loop callback: with many
            # bidders most of an auction's cost was a callback per message.
            pending = self._pending
            pending.append((topic, subs, msg))
            if len(pending) == 1:
                loop.call_soon(self._drain)
        else:
            loop.call_soon_threadsafe(self._deliver, topic, subs, msg)

    def publish_many(self, topic: str, messages: Sequence[object]) -> None:
        """Publish ``messages`` on ``topic`` in order, as ``publish`` one by one would,
        in one call: the end of an auction among N bidders is N-1 REJECTs, and a
        performer's change of state one status per action it serves. The drain is
        scheduled when the first message would have scheduled it."""
        subs = self._subscribers.get(topic)
        loop = self._loop
        if (
            self._closed
            or not subs
            or loop is None
            or threading.get_ident() != self._loop_thread
            or (not self._pending and loop is not _get_running_loop() and loop.is_closed())
        ):
            # closed, nobody listening, not started, another thread or a closed loop:
            # publish says what happens
            for msg in messages:
                self.publish(topic, msg)
            return
        if not messages:
            return
        pending = self._pending
        if not pending:
            loop.call_soon(self._drain)
        self.published += len(messages)
        batches = subs[0].batches if len(subs) == 1 else None
        if batches is not None:
            # one subscriber that takes batches (a hub's router): one entry, one call
            pending.append((topic, batches, list(messages)))
        else:
            pending.extend(zip(repeat(topic), repeat(subs), messages))

    def publish_batch(self, messages: list[tuple[str, object]]) -> None:
        """Publish ``(topic, msg)`` pairs in order, from any thread.

        From another thread the whole batch costs one ``call_soon_threadsafe`` (one
        wake-up of the loop) instead of one per message: what a DDS reader thread
        took in one go is delivered in one go.
        """
        if threading.get_ident() == self._loop_thread or self._loop is None:
            for topic, msg in messages:
                self.publish(topic, msg)
            return
        if self._closed:
            raise HubError("cannot publish: transport closed")
        self.published += len(messages)
        batch = [
            (topic, subs, msg) for topic, msg in messages if (subs := self._subscribers.get(topic))
        ]
        if batch:
            self._loop.call_soon_threadsafe(self._deliver_batch, batch)

    def _deliver_batch(self, batch: list[tuple[str, list[_InProcessSubscription], object]]) -> None:
        for topic, subs, msg in batch:
            self._deliver(topic, subs, msg)

    def _drain(self) -> None:
        """Deliver what was published before this callback ran (later messages wait for
        the next one, so callbacks scheduled meanwhile keep their turn)."""
        batch, self._pending = self._pending, []
        loop = self._loop
        for topic, subs, msg in batch:
            # _deliver's loop, inlined: a call less per message of an auction
            for sub in subs:
                if not sub.closed:
                    try:
                        sub.callback(msg)
                    except Exception as exc:
                        report_subscriber_error(loop, topic, exc)

    def _deliver(self, topic: str, subs: list[_InProcessSubscription], msg: object) -> None:
        for sub in subs:
            if sub.closed:
                continue
            try:
                sub.callback(msg)
            except Exception as exc:
                report_subscriber_error(self._loop, topic, exc)


def redirect(
    subscription: Subscription,
    callback: Callback,
    many: Callable[[Sequence[object]], None] | None = None,
) -> bool:
    """Hand what ``subscription`` receives to ``callback`` from now on, messages already
    queued included, and with ``many`` the batches of ``publish_many`` to ``many`` in
    one call each, where the transport allows it (in-process: yes); False where not.

    A hub's router for a topic it does not route, with a single subscriber, passes
    that subscriber to the transport instead of being called for each message; a
    routed topic's router takes the REJECTs that end an auction as one batch."""
    if isinstance(subscription, _InProcessSubscription) and not subscription.closed:
        subscription.callback = callback
        subscription.many = many
        batch = subscription.batch
        if many is not None:
            if batch is None:
                batch = subscription.batch = _Batches(subscription)
            batch.callback = many
            subscription.batches = [batch]
        else:
            if batch is not None:  # batches already queued go one by one
                batch.callback = batch.one_by_one
            subscription.batches = None
        return True
    return False


def report_subscriber_error(
    loop: asyncio.AbstractEventLoop | None, topic: str, exc: Exception
) -> None:
    """A subscriber raised: tell the loop's exception handler (which logs it) and go on
    delivering to the others."""
    context = {
        "message": f"subscriber of {topic!r} raised {type(exc).__name__}: {exc}",
        "exception": exc,
    }
    if loop is not None:
        loop.call_exception_handler(context)
    else:  # pragma: no cover - delivery always runs on a loop
        log.error(context["message"], exc_info=exc)
