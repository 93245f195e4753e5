"""Ctrl-C reaches the command even when an orderly shutdown swallows the cancel."""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal

import pytest

from plansys_bridge.clock import run


def test_an_interrupt_swallowed_by_a_shutdown_still_interrupts() -> None:
    async def main() -> str:
        child = asyncio.create_task(asyncio.sleep(10))
        asyncio.get_running_loop().call_soon(os.kill, os.getpid(), signal.SIGINT)
        with contextlib.suppress(asyncio.CancelledError):
            await child  # the main task's own cancel lands here and is swallowed
        return "finished"

    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        pytest.skip("SIGINT is not Python's default handler here, so asyncio does not take it")
    with pytest.raises(KeyboardInterrupt):
        run(main())


def test_a_coroutine_that_ends_normally_returns_its_value() -> None:
    async def main() -> str:
        with contextlib.suppress(asyncio.CancelledError):
            await asyncio.create_task(asyncio.sleep(0))
        return "finished"

    assert run(main()) == "finished"
