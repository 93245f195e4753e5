"""An operation that hub messages and timers drive to one outcome, kept as a future.

Such an operation (an :class:`~plansys_bridge.hub.auction.ActionClient` following one
action) does its work in the callbacks the hub and the loop call; a task awaiting its
outcome would only add a task object, a step to start it, a wake-up when the outcome
is set and a done-callback round per operation. :class:`DrivenFuture` hands out the
outcome future itself and gives it what the task gave:

* cancelling the future from outside stops the operation (``_abandon``), as
  cancelling the task did (a done callback, taken off again when the operation
  settles the future itself, so an ordinary end schedules no extra call);
* the first step can be run now or in a loop callback scheduled now (where a task's
  first step ran), and what it raises reaches whoever awaits the future;
* ``_settled_cb``, when given, is called as soon as the future is settled, in the
  same call (or from the done callback after a cancel from outside): what a done
  callback of the owner's would do, without the loop callback the future schedules
  for each (the executor's, once per executed action).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Generic, TypeVar

__all__ = ["DrivenFuture"]

T = TypeVar("T")


class DrivenFuture(Generic[T]):
    """Base class: ``_launch`` (the first step) and ``_abandon`` (stop, after a cancel
    from outside or a failed first step) are the subclass's, and so is making the
    outcome future ``_done`` (``loop.create_future()``, watched by :meth:`_on_done`)."""

    _done: asyncio.Future[T] | None = None
    _loop: asyncio.AbstractEventLoop
    """The running loop, set when the future is made: only what runs after reads it."""
    _settled_cb: Callable[[], None] | None = None
    """Called once, right after the future is settled (see module docs)."""

    def _launch(self) -> None:  # pragma: no cover - every subclass implements it
        raise NotImplementedError

    def _abandon(self) -> None:  # pragma: no cover - every subclass implements it
        raise NotImplementedError

    def _begin(self, done: asyncio.Future[T]) -> Exception | None:
        """Run the first step, unless the future was cancelled first (as a task
        cancelled before its first step never ran). Returns what the step raised,
        the operation then stopped and the future no longer watched."""
        if done.done():
            return None
        try:
            self._launch()
        except BaseException as exc:
            self._abandon()
            if not isinstance(exc, Exception):
                raise
            self._settled()
            return exc
        return None

    def _begin_soon(self, done: asyncio.Future[T]) -> None:
        """:meth:`_begin` as a loop callback (inlined: once per operation): an error
        goes to the future, where a task would have held it."""
        if done.done():
            return
        try:
            self._launch()
        except Exception as exc:
            self._abandon()
            self._settled()
            done.set_exception(exc)
            self._notify()
        except BaseException:
            self._abandon()
            raise

    def _on_done(self, done: asyncio.Future[T]) -> None:
        """The future ended without the operation settling it: cancelled from outside."""
        if done.cancelled():
            self._abandon()
            self._notify()

    def _notify(self) -> None:
        """Call ``_settled_cb`` (once): the future has just been settled."""
        settled = self._settled_cb
        if settled is not None:
            self._settled_cb = None
            settled()

    def _settled(self) -> asyncio.Future[T] | None:
        """The future if it is the operation's to settle now (still pending), no longer
        watched for a cancel from outside; else None."""
        done = self._done
        if done is None or done.done():
            return None
        done.remove_done_callback(self._on_done)
        return done

    def _resolve(self, value: T) -> None:
        """Settle the future with ``value`` (:meth:`_settled` inlined: once per operation)."""
        done = self._done
        if done is not None and not done.done():
            done.remove_done_callback(self._on_done)
            done.set_result(value)
            self._notify()

    def _reject(self, exc: BaseException) -> None:
        done = self._settled()
        if done is not None:
            done.set_exception(exc)
            self._notify()
