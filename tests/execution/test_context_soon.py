"""PlanContext.soon: the first steps a tick starts, run in one loop callback.

What the executor asks for within one tick (each auction client's first step) runs
in the order asked, in one loop callback at the place the first would have taken,
so the loop sees the same order as with a callback each; a step that raises reaches
the loop as a callback's error would, and the steps after it still run.
"""

from __future__ import annotations

import asyncio
from typing import Any

from test_resting_wakeups import _context


def test_what_one_tick_asks_for_runs_in_order_in_one_loop_callback() -> None:
    ctx = _context()
    seen: list[Any] = []

    async def body() -> None:
        loop = asyncio.get_running_loop()
        loop.call_soon(seen.append, "before")
        for i in range(3):
            ctx.soon(seen.append, i)
        loop.call_soon(seen.append, "after")
        queued = len(loop._ready)  # type: ignore[attr-defined]
        await asyncio.sleep(0)
        ctx.soon(seen.append, "next tick")
        await asyncio.sleep(0)
        seen.append(("callbacks queued for five asks", queued))

    asyncio.run(body())
    assert seen == ["before", 0, 1, 2, "after", "next tick", ("callbacks queued for five asks", 3)]


def test_a_step_that_raises_reaches_the_loop_and_the_rest_still_run() -> None:
    ctx = _context()
    seen: list[Any] = []
    errors: list[Any] = []

    def boom() -> None:
        raise RuntimeError("first step failed")

    async def body() -> None:
        loop = asyncio.get_running_loop()
        loop.set_exception_handler(lambda _loop, context: errors.append(context["exception"]))
        ctx.soon(seen.append, 1)
        ctx.soon(boom)
        ctx.soon(seen.append, 2)
        ctx.soon(seen.append, 3)
        for _ in range(3):
            await asyncio.sleep(0)

    asyncio.run(body())
    assert seen == [1, 2, 3]
    assert [repr(e) for e in errors] == [repr(RuntimeError("first step failed"))]
