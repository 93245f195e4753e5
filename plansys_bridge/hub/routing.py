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

A performer specialised to some arguments (``move`` for robot ``r2`` only) subscribes
with a specialised key, ``("action", "move", ("r2",))``: a REQUEST reaches it only when
its arguments match (PlanSys2's rule, :func:`arguments_match`). Ten robots each serving
their own ``move`` used to hear every ``move`` REQUEST and refuse nine in ten after
reading it; now the hub picks the one by a dictionary look-up on the argument.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Hashable, Iterable, Sequence
from heapq import merge
from itertools import count
from typing import Any

from plansys_bridge.hub.client_table import ClientTable
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.hub.transport import Subscription, redirect, report_subscriber_error

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
_TO_NODE = frozenset({ExecutionType.CONFIRM, ExecutionType.REJECT, ExecutionType.CANCEL})
"""The kinds :func:`_action_route` routes by node (neither REQUEST nor to a client)."""


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


def performer_keys(
    node_name: str, actions: Iterable[str] | dict[str, Sequence[str]]
) -> list[Hashable]:
    """What a performer hears on ``actions_hub``: REQUESTs for its actions, and the
    CONFIRM/REJECT/CANCEL messages naming it.

    ``actions`` as a mapping of action name to specialised arguments routes a REQUEST
    only to performers whose specialised arguments match it; as plain names (or with
    no specialised argument) every REQUEST of the action arrives."""
    if isinstance(actions, dict):
        keys: list[Hashable] = [
            ("action", a, tuple(spec)) if any(spec) else ("action", a)
            for a, spec in actions.items()
        ]
    else:
        keys = [("action", a) for a in actions]
    keys.append(("node", node_name))
    return keys


def arguments_match(specialized: Sequence[str], arguments: Sequence[str]) -> bool:
    """PlanSys2's rule: compare position by position, ``""`` matches anything.

    No specialised arguments matches every call. Lengths may differ (PlanSys2 only
    warns): the positions both have are compared.
    """
    # A loop rather than all(...): no generator made per call (a REQUEST's check).
    for s, a in zip(specialized, arguments, strict=False):  # noqa: SIM110
        if s != "" and s != a:
            return False
    return True


def _specialised(key: Hashable) -> tuple[str, tuple[str, ...]] | None:
    """``(action, spec)`` of a specialised performer key, else None."""
    if isinstance(key, tuple) and len(key) == 3 and key[0] == "action":
        return key[1], key[2]
    return None


def client_keys(request_id: str, action: str, arguments: Iterable[str]) -> list[Hashable]:
    """What an auction client hears: answers carrying its request id, and answers
    without one that name its action text (PlanSys2 matches on the text alone)."""
    keys: list[Hashable] = [("text", action, tuple(arguments))]
    if request_id:
        keys.append(("request", request_id))
    return keys


class _RoutedSubscription:
    __slots__ = ("callback", "closed", "keys", "many", "order", "router", "routes", "specs")

    def __init__(
        self, router: TopicRouter, callback: Callback, keys: tuple[Hashable, ...] | None, order: int
    ) -> None:
        self.router = router
        self.callback = callback
        self.many: Callable[[Sequence[object]], None] | None = None
        """Takes a ``publish_many`` batch in one call, while it is the topic's only
        subscriber on a topic without routes (the liveness table)."""
        self.keys = keys
        self.order = order
        self.closed = False
        self.specs: dict[str, tuple[str, ...]] = {}
        """Action name -> specialised arguments, for the specialised keys."""
        self.routes: list[Hashable] = []
        """The route keys it is listed under in its router's ``_keyed``."""

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self.router._remove(self)

    def __lt__(self, other: Any) -> bool:
        return bool(self.order < other.order)

    def __gt__(self, other: Any) -> bool:
        """(A table's client, which has no ``<`` of its own, compares by this.)"""
        return bool(self.order > other.order)

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"<Subscription {self.router.topic!r} keys={self.keys} {state}>"


_FOUND_KEPT = 4096
"""Argument tuples a specialised index keeps the candidates of (then it starts over)."""


class _SpecialisedIndex:
    """The performers of one action specialised to some arguments, by the first
    argument each one fixes: a REQUEST finds its candidates with one look-up per
    position in use (usually one: the robot)."""

    __slots__ = ("found", "positions")

    def __init__(self, action: str, subs: Iterable[_RoutedSubscription]) -> None:
        tables: dict[int, dict[str, list[tuple[_RoutedSubscription, tuple[str, ...], bool]]]] = {}
        for sub in subs:
            spec = sub.specs[action]
            fixed = [i for i, value in enumerate(spec) if value]
            position = fixed[0]
            # One fixed argument: the look-up is the whole check.
            entry = (sub, spec, len(fixed) == 1)
            tables.setdefault(position, {}).setdefault(spec[position], []).append(entry)
        self.positions = tuple(sorted(tables.items()))
        self.found: dict[Any, list[_RoutedSubscription]] = {}
        """:meth:`candidates` by the arguments asked for: a plan runs the same ground
        actions again and again (the index is rebuilt, empty, when its subscribers
        change, so a kept answer never goes stale). Never changed once handed out."""

    def candidates(self, arguments: Sequence[str]) -> list[_RoutedSubscription]:
        """The subscribers whose specialised arguments match, in subscription order."""
        kept = arguments.__class__ is tuple
        if kept:
            known = self.found.get(arguments)
            if known is not None:
                return known
        found: list[_RoutedSubscription] = []
        merged = len(self.positions) > 1
        for position, table in self.positions:
            if position < len(arguments):
                entries: Iterable[tuple[_RoutedSubscription, tuple[str, ...], bool]] = table.get(
                    arguments[position], ()
                )
            else:  # PlanSys2 compares only the positions both have
                entries = [e for group in table.values() for e in group]
                merged = True
            for sub, spec, single in entries:
                if single or arguments_match(spec, arguments):
                    found.append(sub)
        if merged:
            found.sort()
        if kept:
            if len(self.found) >= _FOUND_KEPT:
                self.found.clear()
            self.found[arguments] = found
        return found


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
        self._all_keyed: dict[_RoutedSubscription, None] = {}
        """Ordered as subscribed; a dict so that a client leaving (once per action)
        does not copy the list of everybody."""
        self._specialised_subs: dict[Hashable, list[_RoutedSubscription]] = {}
        self._specialised: dict[Hashable, _SpecialisedIndex] = {}
        """By the REQUEST route key ``("action", name)``."""
        self._router = _ROUTERS.get(topic)
        self._order = count()
        self.clients = ClientTable(self._order)
        """The auction clients, by request id (:mod:`~plansys_bridge.hub.client_table`):
        one dictionary entry per client instead of a subscription."""
        self._transport_subscription: Subscription | None = None

    def add(
        self,
        callback: Callback,
        keys: Iterable[Hashable] | None,
        many: Callable[[Sequence[object]], None] | None = None,
    ) -> Subscription:
        """Subscribe ``callback`` (see :meth:`Hub.subscribe`); ``many``, if given, takes
        the batches of ``publish_many`` in one call while ``callback`` is the only
        subscriber of a topic without routes."""
        key_tuple = None if keys is None else tuple(dict.fromkeys(keys))
        sub = _RoutedSubscription(self, callback, key_tuple, next(self._order))
        sub.many = many
        if key_tuple is None or self._router is None:
            self._everyone = [*self._everyone, sub]
            self._rewire()
            return sub
        for key in key_tuple:
            # _specialised, for the keys that may be one (a client's never are)
            specialised = (
                _specialised(key) if key.__class__ is not tuple or key[0] == "action" else None
            )
            if specialised is not None and any(specialised[1]):
                action, spec = specialised
                sub.specs[action] = spec
                route = ("action", action)
                self._specialised_subs[route] = [*self._specialised_subs.get(route, ()), sub]
                self._specialised[route] = _SpecialisedIndex(action, self._specialised_subs[route])
            else:
                if specialised is not None:  # nothing fixed: every REQUEST of the action
                    key = ("action", specialised[0])
                self._keyed[key] = [*self._keyed.get(key, ()), sub]
                sub.routes.append(key)
        self._all_keyed[sub] = None
        return sub

    def _remove(self, sub: _RoutedSubscription) -> None:
        if sub in self._everyone:
            self._everyone = [s for s in self._everyone if s is not sub]
            self._rewire()
            return
        keyed = self._keyed
        for key in sub.routes:
            subs = keyed.get(key, ())
            if len(subs) == 1 and subs[0] is sub:
                # its own route (a client's request id): no list to filter, once per action
                del keyed[key]
                continue
            remaining = [s for s in subs if s is not sub]
            if remaining:
                keyed[key] = remaining
            else:
                keyed.pop(key, None)
        for action in sub.specs:
            route = ("action", action)
            left = [s for s in self._specialised_subs.get(route, ()) if s is not sub]
            if left:
                self._specialised_subs[route] = left
                self._specialised[route] = _SpecialisedIndex(action, left)
            else:
                self._specialised_subs.pop(route, None)
                self._specialised.pop(route, None)
        self._all_keyed.pop(sub, None)

    @property
    def transport_subscription(self) -> Subscription | None:
        """The transport's subscription feeding this router (set by the hub)."""
        return self._transport_subscription

    @transport_subscription.setter
    def transport_subscription(self, sub: Subscription | None) -> None:
        self._transport_subscription = sub
        if sub is not None and self._router is not None:
            redirect(sub, self.dispatch, self.dispatch_many)  # batches in one call
        self._rewire()

    def _rewire(self) -> None:
        """Where the transport delivers on a topic without routes: with one subscriber,
        to that subscriber itself (a call less per message: a performer's statuses
        reach the liveness table so, a change of state's in one call); else to
        :meth:`dispatch`. Closing the subscriber
        rewires before anything else is delivered."""
        sub = self._transport_subscription
        if sub is None or self._router is not None:
            return  # a routed topic: always dispatch (keyed subscribers never rewire)
        everyone = self._everyone
        if len(everyone) == 1:
            redirect(sub, everyone[0].callback, everyone[0].many)
        else:
            redirect(sub, self.dispatch)

    def __len__(self) -> int:
        return len(self._everyone) + len(self._all_keyed) + len(self.clients.everyone())

    def _targets(self, key: Hashable, msg: object) -> list[_RoutedSubscription] | tuple[()]:
        """The keyed subscribers ``msg`` (routed by ``key``) is for, in order."""
        keyed = self._keyed.get(key, ())
        index = self._specialised.get(key) if self._specialised else None
        if index is None or not isinstance(msg, ActionExecution):
            return keyed
        found = index.candidates(msg.arguments)
        if not keyed:
            return found
        return list(merge(keyed, found)) if found else keyed

    def _with_clients(self, key: Hashable, keyed: Sequence[Any]) -> Sequence[Any]:
        """``keyed`` and the table's clients that ``key`` names, merged in order."""
        table = self.clients
        if not table.by_request or key.__class__ is not tuple:
            return keyed
        kind = key[0]
        if kind == "request":
            found: Sequence[Any] = table.for_request(key[1])
        elif kind == "text":
            found = table.for_text(key[1], key[2])
        else:
            return keyed
        if not found:
            return keyed
        return list(merge(keyed, found)) if keyed else found

    def wants(self, msg: object) -> bool:
        """Would :meth:`dispatch` deliver ``msg`` to anybody now? A DDS transport asks
        this of each message it publishes, 400 per auction among 200 bidders: a
        RESPONSE or REJECT is answered with the look-ups dispatch places it by."""
        if self._everyone:
            return True
        if self._router is _action_route and msg.__class__ is ActionExecution:
            kind = msg.type
            rid = msg.request_id
            fast: Hashable | None = None
            if kind in _TO_NODE:
                fast = ("node", msg.node_id)
            elif rid and kind in _TO_CLIENT:
                if rid in self.clients.by_request:
                    return True
                fast = ("request", rid)
            if fast is not None and not (self._specialised and fast in self._specialised):
                return bool(self._keyed.get(fast))
        key = self._router(msg) if self._router is not None else None
        if key is None:
            return bool(self._all_keyed) or bool(self.clients.by_request)
        return bool(self._with_clients(key, self._targets(key, msg)))

    def dispatch(self, msg: object) -> None:
        """Deliver ``msg`` (called by the transport on the loop)."""
        everyone = self._everyone
        router = self._router
        key: Hashable | None
        targets: Iterable[Any] | None = None
        if router is _action_route and msg.__class__ is ActionExecution:
            # _action_route, inlined: every message of every auction comes by here
            kind = msg.type
            if kind is _REQUEST:
                key = ("action", msg.action)
            elif kind in _TO_CLIENT:
                rid = msg.request_id
                if not rid:
                    key = _action_route(msg)
                else:
                    key = ("request", rid)
                    held = self.clients.by_request.get(rid)
                    if held is not None:
                        # the client(s) of the table (ClientTable.for_request, inlined)
                        mine: Sequence[Any] = held if held.__class__ is list else (held,)
                        others = self._keyed.get(key)
                        if others:
                            mine = list(merge(others, mine))
                        targets = merge(everyone, mine) if everyone else mine
            else:
                key = ("node", msg.node_id)
        elif router is None:  # a topic without routes: everybody is in _everyone
            key = None
        else:
            key = router(msg)
        if targets is not None:
            pass
        elif key is None:
            all_keyed: list[Any] = list(self._all_keyed)
            if self.clients.by_request:
                all_keyed = sorted([*all_keyed, *self.clients.everyone()], key=_order)
            targets = merge(everyone, all_keyed) if all_keyed else everyone
        else:
            specialised = self._specialised
            index = specialised.get(key) if specialised else None
            keyed: Sequence[Any]
            if index is None:
                keyed = self._keyed.get(key, ())
            else:
                # _targets, inlined for a REQUEST whose arguments were seen before and
                # that no subscriber of every argument shares: the kept candidates
                arguments = msg.arguments if msg.__class__ is ActionExecution else None
                found = index.found.get(arguments) if arguments.__class__ is tuple else None
                keyed = (
                    found
                    if found is not None and key not in self._keyed
                    else self._targets(key, msg)
                )
            if self.clients.by_request:
                keyed = self._with_clients(key, keyed)
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

    def dispatch_many(self, messages: Sequence[object]) -> None:
        """:meth:`dispatch` for each of ``messages``, in order (a ``publish_many``
        batch). A message naming one node (the REJECTs that end an auction among N
        bidders) goes straight to that node's subscribers while nobody takes every
        message: one call for the batch instead of one per message."""
        for msg in messages:
            if (
                self._everyone
                or self._router is not _action_route
                or msg.__class__ is not ActionExecution
                or msg.type not in _TO_NODE
            ):
                self.dispatch(msg)
                continue
            # dispatch's delivery loop, inlined: a call less per message of the batch
            for sub in self._keyed.get(("node", msg.node_id), ()):
                if sub.closed:
                    continue
                try:
                    sub.callback(msg)
                except Exception as exc:
                    report_subscriber_error(_running_loop(), self.topic, exc)

    def close(self) -> None:
        for sub in (*self._everyone, *self._all_keyed):
            sub.closed = True
        self._everyone, self._keyed, self._all_keyed = [], {}, {}
        self._specialised_subs, self._specialised = {}, {}
        self.clients.close()
        if self._transport_subscription is not None:
            self._transport_subscription.close()


def _order(sub: Any) -> int:
    return int(sub.order)


def _running_loop() -> Any:
    try:
        return asyncio.get_running_loop()
    except RuntimeError:  # pragma: no cover - delivery always runs on a loop
        return None
