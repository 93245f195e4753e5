"""The state an :class:`~plansys_bridge.hub.auction.ActionClient` keeps, and its defaults.

Why a class of its own: a client is made per executed action and most of its state
never changes for it, so each field's starting value is a class attribute (an
immutable one) read until the client sets its own; making a client then writes
only what differs. Listed here, apart from the auction's logic, they read as the
client's state at a glance.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from plansys_bridge.hub.auction_policy import ClientPhase, FeedbackCallback
from plansys_bridge.hub.client_table import ClientTable
from plansys_bridge.hub.freed_watch import FreedWatch, Waiter
from plansys_bridge.hub.liveness import LivenessTable

__all__ = ["ClientState"]


class ClientState:
    """Base class of :class:`~plansys_bridge.hub.auction.ActionClient`: its state."""

    # Defaults read from the class until a client sets its own (immutable values):
    # a client is made per executed action and most of these never change for it.
    phase: ClientPhase = ClientPhase.NEW
    performer = ""
    """The confirmed performer's node name, once there is one."""
    completion = 0.0
    status = ""
    requests_sent = 0
    _cancel_requested = False
    _cancel_sent_to: str | None = None
    _last_seen = 0.0
    _confirm_cb: Callable[[str], None] | None = None
    _feedback_cb: FeedbackCallback | None = None
    _freed = False
    """A matching performer went from RUNNING to READY: worth asking again now."""
    _liveness: LivenessTable | None = None
    # In the hub's table of clients (:mod:`.client_table`) once it listens: its place
    # among the subscribers, whether it left, what the router calls (_on_action_msg)
    _table: ClientTable | None = None
    order = 0
    closed = False
    callback: Callable[[object], None]
    _alarm = 0
    """The number of the client's live alarm on its loop's :class:`~.alarms.Alarms`
    (0: none)."""
    _alarm_at = math.inf
    """When that alarm rings."""
    _watch: FreedWatch
    """The hub's clients waiting for a performer (:mod:`.freed_watch`)."""
    _waiting: dict[Waiter, None] | None = None
    """Where this client waits in ``_watch`` while in auction."""
    # the action's auctions (one, more after a lost performer)
    _excluded: frozenset[str] = frozenset()
    _lost: tuple[str, ...] = ()
    _reauctioned = 0
    # the current auction (set by _begin_auction)
    _start = 0.0
    _give_up_at = 0.0
    _sent = 0
    _bids: list[tuple[float, int, str]]
    _seen: set[str]
    _bid_deadline = math.inf
