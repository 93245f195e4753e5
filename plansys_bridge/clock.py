"""Clocks: the wall clock, and a virtual clock that runs hours of mission time in seconds.

Every timing decision in the project goes through asyncio (``loop.time()``,
``asyncio.sleep``, ``loop.call_later``, ``asyncio.wait_for``), so the same code runs
on both clocks. The virtual clock does not patch anything: it runs the program on a
:class:`VirtualTimeEventLoop`, an asyncio loop whose ``time()`` is virtual and which,
when nothing is ready to run, jumps straight to the next scheduled timer instead of
sleeping. Runs are deterministic because the order of callbacks depends only on the
program, never on how long each step took.

Two kinds of time are kept apart:

* *loop time* (``loop.time()``): what protocol timeouts use (auction retries,
  heartbeats, liveness). On the wall clock these are real seconds.
* *mission time* (:meth:`Clock.now`, :meth:`Clock.sleep`): what action durations and
  message stamps use. ``WallClock(time_scale=0.05)`` runs every mission duration 20x
  faster than real time; the virtual clock's mission time is its loop time.
"""

from __future__ import annotations

import asyncio
import selectors
import threading
import time
from collections.abc import Callable, Coroutine, Mapping
from concurrent.futures import Executor
from functools import partial
from operator import attrgetter
from typing import Any, Protocol, TypeVar, runtime_checkable

__all__ = [
    "Clock",
    "VirtualClock",
    "VirtualTimeEventLoop",
    "WallClock",
    "run",
    "stamp_loop",
]

T = TypeVar("T")

_get_running_loop = asyncio._get_running_loop
_virtual_now_of = attrgetter("_virtual_now")
"""The running loop or None (``get_running_loop`` without the exception when none)."""


@runtime_checkable
class Clock(Protocol):
    """What the executor, performers and adapters need to know about time."""

    time_scale: float
    """Real seconds per mission second (1.0: real time; 0.05: 20x faster)."""

    def now(self) -> float:
        """Mission time in seconds, used for stamps and efficiency figures."""
        ...

    async def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` of mission time."""
        ...


class WallClock:
    """Real time, optionally scaled.

    ``now()`` starts at the Unix time of construction and then advances
    ``1 / time_scale`` mission seconds per real second, so stamps look like real
    dates while a scaled run still reports mission-time durations.
    """

    def __init__(self, time_scale: float = 1.0) -> None:
        if not time_scale > 0:
            raise ValueError(f"time_scale must be > 0, got {time_scale!r}")
        self.time_scale = float(time_scale)
        self._epoch = time.time()
        self._origin = time.monotonic()

    def now(self) -> float:
        return self._epoch + (time.monotonic() - self._origin) / self.time_scale

    async def sleep(self, seconds: float) -> None:
        await asyncio.sleep(max(0.0, seconds) * self.time_scale)

    def new_loop(self) -> asyncio.AbstractEventLoop:
        return asyncio.new_event_loop()

    def __repr__(self) -> str:
        return f"WallClock(time_scale={self.time_scale})"


class _VirtualSelector(selectors.BaseSelector):
    """Selector wrapper that turns "block until the next timer" into a time jump.

    asyncio's loop asks its selector to wait exactly as long as the earliest timer
    needs. This wrapper first polls the real selector without blocking (so real
    sockets and ``call_soon_threadsafe`` wake-ups are never starved) and, if nothing
    happened, advances the loop's virtual time to that timer instead of sleeping.
    While work submitted with ``run_in_executor`` is still running in a thread, time
    holds still and the wrapper waits for real, so a planner call costs no mission time.
    (Long-lived background work therefore belongs in its own thread, not in the
    loop's executor: a job that never ends would hold virtual time still forever.)
    """

    _THREAD_POLL = 0.05  # real seconds between checks while executor jobs run

    def __init__(self, loop: VirtualTimeEventLoop, real: selectors.BaseSelector) -> None:
        self._loop = loop
        self._real = real

    def register(self, fileobj: Any, events: int, data: Any = None) -> selectors.SelectorKey:
        return self._real.register(fileobj, events, data)

    def unregister(self, fileobj: Any) -> selectors.SelectorKey:
        return self._real.unregister(fileobj)

    def modify(self, fileobj: Any, events: int, data: Any = None) -> selectors.SelectorKey:
        return self._real.modify(fileobj, events, data)

    def get_key(self, fileobj: Any) -> selectors.SelectorKey:
        return self._real.get_key(fileobj)

    def get_map(self) -> Mapping[Any, selectors.SelectorKey]:
        return self._real.get_map()

    def close(self) -> None:
        self._real.close()

    def select(self, timeout: float | None = None) -> list[tuple[selectors.SelectorKey, int]]:
        if timeout is not None and timeout <= 0:
            return self._real.select(0)
        events = self._real.select(0)
        if events:
            return events
        loop = self._loop
        if loop._executor_jobs > 0:
            # Real work is under way in a thread: wait for it in real time.
            return self._real.select(self._THREAD_POLL)
        if timeout is None:
            # No timer at all: only a real event (another thread, a socket) can
            # wake the program, exactly as on the wall clock.
            return self._real.select(None)
        loop._advance_to_next_timer(timeout)
        return []


class VirtualTimeEventLoop(asyncio.SelectorEventLoop):
    """An asyncio loop whose clock is virtual and jumps to the next timer when idle."""

    def __init__(self, start: float = 0.0) -> None:
        self._virtual_now = float(start)
        self._executor_jobs = 0
        self._jumps = 0
        real = selectors.DefaultSelector()
        super().__init__(selector=_VirtualSelector(self, real))
        if type(self).time is _plain_time:
            # time(), read by asyncio on every pass and every timer and by the
            # protocol's timeouts (about ten times per executed action), as a C
            # callable: the attribute read without a Python frame (half the cost).
            # A subclass with its own time() keeps it.
            self.time = partial(_virtual_now_of, self)  # type: ignore[method-assign]

    def time(self) -> float:
        return self._virtual_now

    @property
    def jumps(self) -> int:
        """How many times virtual time skipped ahead (a measure of idle stretches)."""
        return self._jumps

    def _advance_to_next_timer(self, timeout: float) -> None:
        scheduled = getattr(self, "_scheduled", None)
        target = self._virtual_now + timeout
        if scheduled:
            # asyncio caps one wait at 24 h; jump straight to the timer anyway.
            target = max(target, scheduled[0].when())
        if target > self._virtual_now:
            self._virtual_now = target
            self._jumps += 1

    def advance(self, seconds: float) -> None:
        """Move virtual time forward by hand (timers due by then run on the next pass)."""
        if seconds < 0:
            raise ValueError("virtual time cannot go backwards")
        self._virtual_now += seconds

    def run_in_executor(  # type: ignore[override]
        self, executor: Executor | None, func: Callable[..., T], *args: Any
    ) -> asyncio.Future[T]:
        future = super().run_in_executor(executor, func, *args)
        self._executor_jobs += 1
        future.add_done_callback(self._executor_job_done)
        return future

    def _executor_job_done(self, _future: asyncio.Future[Any]) -> None:
        self._executor_jobs -= 1


_plain_time = VirtualTimeEventLoop.time
"""The class's own ``time`` (a subclass's, or one patched in, is kept)."""


class VirtualClock:
    """Mission time that only advances when the program waits.

    ``now()`` is the running :class:`VirtualTimeEventLoop`'s time. Use
    :func:`run` (or :meth:`new_loop`) so the program runs on such a loop.
    """

    time_scale = 1.0

    def __init__(self, start: float = 0.0) -> None:
        self._start = float(start)
        self._loop: VirtualTimeEventLoop | None = None
        self._lock = threading.Lock()
        self._last_running: VirtualTimeEventLoop | None = None
        """The virtual loop ``now()`` last found running, whose ``time()`` is the
        base class's: while it still runs, its time is read without asking again
        what kind of loop it is (an executed action reads the clock about ten times)."""

    def new_loop(self) -> VirtualTimeEventLoop:
        loop = VirtualTimeEventLoop(start=self._start)
        with self._lock:
            self._loop = loop
        return loop

    @property
    def loop(self) -> VirtualTimeEventLoop | None:
        return self._loop

    def now(self) -> float:
        running = _get_running_loop()
        last = self._last_running
        if running is last and last is not None:
            return last._virtual_now
        return self._now_in(running)

    def _now_in(self, running: asyncio.AbstractEventLoop | None) -> float:
        """``now()`` when ``running`` is not the loop it last found (a new loop, another
        thread's, none, or a loop whose ``time()`` is its own)."""
        if isinstance(running, VirtualTimeEventLoop):
            if type(running).time is VirtualTimeEventLoop.time:
                self._last_running = running
            return running.time()
        if self._loop is not None:
            return self._loop.time()
        return self._start

    async def sleep(self, seconds: float) -> None:
        loop = asyncio.get_running_loop()
        if not isinstance(loop, VirtualTimeEventLoop):
            raise RuntimeError(
                "VirtualClock.sleep() needs a VirtualTimeEventLoop; "
                "start the program with plansys_bridge.clock.run(coro, clock)"
            )
        await asyncio.sleep(max(0.0, seconds))

    def __repr__(self) -> str:
        return f"VirtualClock(start={self._start})"


def stamp_loop(clock: Clock, loop: asyncio.AbstractEventLoop | None) -> VirtualTimeEventLoop | None:
    """``loop`` when ``clock.now()`` is ``loop._virtual_now`` whenever ``loop`` runs
    (a :class:`VirtualClock` on its :class:`VirtualTimeEventLoop`, neither with its own
    ``now``/``time``), else None.

    Who stamps often on one loop (a performer: its statuses on every change of state,
    two per action it executes) reads the attribute while that loop is the running one
    instead of calling ``now()``; the stamp is the same."""
    if (
        isinstance(clock, VirtualClock)
        and type(clock).now is VirtualClock.now
        and isinstance(loop, VirtualTimeEventLoop)
        and type(loop).time is VirtualTimeEventLoop.time
    ):
        return loop
    return None


def run(coro: Coroutine[Any, Any, T], clock: Clock | None = None, *, debug: bool = False) -> T:
    """``asyncio.run`` on the loop ``clock`` needs (a virtual-time loop for VirtualClock)."""
    # A clock may say which loop it needs (``new_loop``); the default loop otherwise.
    factory = getattr(clock, "new_loop", None) or asyncio.new_event_loop
    with asyncio.Runner(debug=debug, loop_factory=factory) as runner:
        return runner.run(_cancellation_kept(coro))


async def _cancellation_kept(coro: Coroutine[Any, Any, T]) -> T:
    """Run ``coro``; if the main task was cancelled and that got lost, cancel after all.

    Ctrl-C (and SIGTERM, see :mod:`plansys_bridge.cli.signals`) cancels the main task,
    and ``asyncio.Runner`` turns that into KeyboardInterrupt only if the task ends
    cancelled. An orderly shutdown that awaits its own tasks under
    ``suppress(CancelledError)``, or Python 3.11's ``wait_for`` finishing as the
    cancel arrives, can swallow it, and the command would exit 0 as if nothing had
    happened. A task still marked as cancelling at the end was interrupted.
    """
    result = await coro
    task = asyncio.current_task()
    if task is not None and task.cancelling():
        raise asyncio.CancelledError
    return result
