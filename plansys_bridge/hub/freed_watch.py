"""The auction clients of one hub waiting for a performer, by action.

A client in auction asks again at once when a performer of its action goes from
RUNNING to READY (:meth:`LivenessTable.watch <plansys_bridge.hub.liveness.LivenessTable.watch>`).
Watching per client cost a watch, an unwatch and a closure per executed action; here
one watcher per action stands for every client waiting for that action, taken from the
table when the last of them stops waiting. A client joins and leaves with dictionary
operations (:meth:`ActionClient._begin_auction <plansys_bridge.hub.auction.ActionClient>`
does them itself); the clients are told in the order they began waiting, as their
own watchers were called.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import ClassVar, Protocol
from weakref import WeakKeyDictionary, ref

from plansys_bridge.hub.liveness import LivenessTable
from plansys_bridge.hub.messages import ActionPerformerStatus

__all__ = ["FreedWatch", "Waiter", "watch_of"]


class Waiter(Protocol):
    def _on_freed(self, msg: ActionPerformerStatus) -> None: ...


class FreedWatch:
    """The waiting clients of one liveness table (see the module's docstring)."""

    last: ClassVar[FreedWatch | None] = None
    """The one :func:`watch_of` gave last: a client finds its hub's here, with no call,
    while one hub serves them all (check ``last.liveness() is liveness``)."""

    def __init__(self, liveness: LivenessTable) -> None:
        self.liveness = ref(liveness)
        """The table, weakly: the table of tables must not keep one alive."""
        self.waiting: dict[str, dict[Waiter, None]] = {}
        """Action -> the clients waiting for a performer of it, in order."""
        self._unwatch: dict[str, Callable[[], None]] = {}

    def first(self, action: str, client: Waiter) -> dict[Waiter, None]:
        """``client`` is the first to wait for ``action``: watch it. Returns the
        clients waiting for it, for ``client`` to leave by itself."""
        waiting = self.waiting[action] = {client: None}
        liveness = self.liveness()
        if liveness is not None:
            self._unwatch[action] = liveness.watch(action, partial(self._freed, action))
        return waiting

    def idle(self, action: str) -> None:
        """The last client waiting for ``action`` left (its dictionary is empty)."""
        del self.waiting[action]
        unwatch = self._unwatch.pop(action, None)
        if unwatch is not None:
            unwatch()

    def _freed(self, action: str, msg: ActionPerformerStatus) -> None:
        waiting = self.waiting.get(action)
        if waiting:
            for client in list(waiting):
                client._on_freed(msg)


_by_table: WeakKeyDictionary[LivenessTable, FreedWatch] = WeakKeyDictionary()


def watch_of(liveness: LivenessTable) -> FreedWatch:
    """The waiting clients of ``liveness`` (made on first use, gone with the table)."""
    watch = _by_table.get(liveness)
    if watch is None:
        watch = _by_table[liveness] = FreedWatch(liveness)
    FreedWatch.last = watch
    return watch
