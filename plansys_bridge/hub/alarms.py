"""Deadlines of many auction clients on one loop timer.

Every executed action's client waits with a deadline (the next REQUEST, the end of
the bid window, the performer's liveness) and nearly always ends before it: a loop
timer per client cost a ``call_at`` (a timer handle, its context, a heap push) and a
``cancel`` per executed action. Here a deadline is a tuple in one heap and ending a
wait is forgetting it: each client holds the number of its live alarm (``_alarm``),
and an entry whose number is no longer its client's is stale. Stale entries at the
head of the heap are dropped whenever an alarm is set, so ended clients are not held
for long; the loop timer is set for the earliest entry, moved earlier when an
earlier one comes, and left alone when its entry goes stale (it then rings for
nothing, once).

Alarms ring as the loop's own timers would: at their deadline (within the loop
clock's resolution) or later, earliest first (in the order set, for equal
deadlines), each in its client's ``_on_timer``; an error goes to the loop's
exception handler.
"""

from __future__ import annotations

import asyncio
import itertools
import math
from heapq import heappop, heappush
from typing import ClassVar, Protocol
from weakref import WeakKeyDictionary, ref

__all__ = ["Alarmed", "Alarms", "alarms_of"]


class Alarmed(Protocol):
    """What an alarm rings: the holder of at most one live alarm."""

    _alarm: int
    """The number of its live alarm (0: none)."""

    def _on_timer(self) -> None: ...


class Alarms:
    """The alarms of one event loop (see the module's docstring)."""

    last: ClassVar[Alarms | None] = None
    """The one :func:`alarms_of` gave last: a client finds its loop's here, with no
    look-up, while one loop serves them all (check ``last.loop() is loop``)."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self.loop = ref(loop)
        """The loop, weakly: the table of alarms by loop must not keep one alive."""
        self._heap: list[tuple[float, int, Alarmed]] = []
        self._numbers = itertools.count(1)
        self._timer: asyncio.TimerHandle | None = None
        self._timer_at = math.inf
        self._ringing = False

    def __len__(self) -> int:
        """Entries held, stale ones included."""
        return len(self._heap)

    def set(self, when: float, who: Alarmed) -> None:
        """Ring ``who._on_timer()`` at ``when`` (loop time), replacing its live alarm."""
        heap = self._heap
        # stale heads go first: an ended client is not held
        while heap and heap[0][2]._alarm != heap[0][1]:
            heappop(heap)
        number = who._alarm = next(self._numbers)
        heappush(heap, (when, number, who))
        if when < self._timer_at and not self._ringing:
            self._move_timer(when)

    def _move_timer(self, when: float) -> None:
        """Set the loop timer for ``when``, in place of the one set before."""
        if self._timer is not None:
            self._timer.cancel()
        self._timer_at = when
        loop = self.loop()
        self._timer = None if loop is None else loop.call_at(when, self._ring)

    @staticmethod
    def clear(who: Alarmed) -> None:
        """Forget ``who``'s live alarm."""
        who._alarm = 0

    def _ring(self) -> None:
        """Ring every live alarm due by the time the loop timer was set for and set
        before this ring, then set the loop timer for the earliest live one left. An
        alarm set while ringing rings on a later pass, as a timer set in a timer's
        callback does."""
        loop = self.loop()
        if loop is None:
            return
        due = max(self._timer_at, loop.time())
        self._timer = None
        self._timer_at = math.inf
        heap = self._heap
        newest = next(self._numbers)  # alarms numbered from here on were set meanwhile
        self._ringing = True
        try:
            while heap:
                when, number, who = heap[0]
                if who._alarm != number:
                    heappop(heap)  # stale: forgotten or replaced
                    continue
                if when > due or number > newest:
                    break
                heappop(heap)
                who._alarm = 0
                try:
                    who._on_timer()
                except Exception as exc:  # what the loop does with a timer's error
                    loop.call_exception_handler(
                        {"message": f"alarm of {who!r} failed", "exception": exc}
                    )
        finally:
            self._ringing = False
            self._rearm()

    def _rearm(self) -> None:
        """Set the loop timer for the earliest live alarm (stale heads dropped)."""
        heap = self._heap
        while heap and heap[0][2]._alarm != heap[0][1]:
            heappop(heap)
        if heap and heap[0][0] < self._timer_at:
            self._move_timer(heap[0][0])


_by_loop: WeakKeyDictionary[asyncio.AbstractEventLoop, Alarms] = WeakKeyDictionary()


def alarms_of(loop: asyncio.AbstractEventLoop) -> Alarms:
    """The alarms of ``loop`` (made on first use, gone with the loop)."""
    alarms = _by_loop.get(loop)
    if alarms is None:
        alarms = _by_loop[loop] = Alarms(loop)
    Alarms.last = alarms
    return alarms
