"""cancel_and_wait: the task's cancel is swallowed, the caller's own is kept."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from plansys_bridge.cancellation import cancel_and_wait


async def _forever() -> None:
    await asyncio.Event().wait()


async def _slow_to_stop(cleaning: asyncio.Event, swallow: bool) -> str:
    """Catches its cancel and cleans up until cancelled again (or forever)."""
    try:
        await _forever()
    except asyncio.CancelledError:
        cleaning.set()
        if not swallow:
            await _forever()
        try:
            await _forever()
        except asyncio.CancelledError:
            return "ignored the second cancel"
    return "unreachable"


async def _old_pattern(task: asyncio.Future[Any]) -> None:
    task.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await task


async def _owner_cancelled_while_waiting(
    stop: Callable[[asyncio.Future[Any]], Awaitable[None]], swallow: bool
) -> tuple[asyncio.Task[None], list[str]]:
    cleaning = asyncio.Event()
    child = asyncio.create_task(_slow_to_stop(cleaning, swallow))
    await asyncio.sleep(0)
    reached: list[str] = []

    async def owner() -> None:
        await stop(child)
        reached.append("carried on after its own cancel")

    task = asyncio.create_task(owner())
    await cleaning.wait()
    task.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await task
    assert child.done()
    return task, reached


@pytest.mark.parametrize("swallow", [False, True], ids=["child-ends-cancelled", "child-returns"])
def test_caller_cancelled_while_waiting_stays_cancelled(swallow: bool) -> None:
    task, reached = asyncio.run(_owner_cancelled_while_waiting(cancel_and_wait, swallow))
    assert task.cancelled()
    assert reached == []


def test_old_pattern_loses_the_callers_cancel() -> None:
    """The pattern cancel_and_wait replaces: the owner is cancelled, yet carries on."""
    task, reached = asyncio.run(_owner_cancelled_while_waiting(_old_pattern, swallow=False))
    assert not task.cancelled()
    assert reached == ["carried on after its own cancel"]


def test_the_tasks_own_cancel_is_swallowed() -> None:
    asyncio.run(_the_tasks_own_cancel_is_swallowed())


async def _the_tasks_own_cancel_is_swallowed() -> None:
    tasks = [asyncio.create_task(_forever()) for _ in range(3)]
    await asyncio.sleep(0)
    await cancel_and_wait(*tasks)
    assert all(task.cancelled() for task in tasks)


def test_a_task_that_failed_raises_its_error() -> None:
    asyncio.run(_a_task_that_failed_raises_its_error())


async def _a_task_that_failed_raises_its_error() -> None:
    async def fails() -> None:
        raise ValueError("sensor gone")

    task = asyncio.create_task(fails())
    await asyncio.sleep(0)
    with pytest.raises(ValueError, match="sensor gone"):
        await cancel_and_wait(task)


def test_done_task_and_cleanup_after_an_earlier_cancel() -> None:
    asyncio.run(_done_task_and_cleanup_after_an_earlier_cancel())


async def _done_task_and_cleanup_after_an_earlier_cancel() -> None:
    """In the finally of a cancelled task, cleanup runs to its end and the cancel goes on."""
    done = asyncio.create_task(asyncio.sleep(0))
    await done
    await cancel_and_wait(done)
    cleaned: list[str] = []

    async def owner() -> None:
        helper = asyncio.create_task(_forever())
        other = asyncio.create_task(_forever())
        try:
            await _forever()
        finally:
            await cancel_and_wait(helper)
            await cancel_and_wait(other)
            cleaned.append("both stopped")

    task = asyncio.create_task(owner())
    await asyncio.sleep(0)
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert cleaned == ["both stopped"]
