"""Stopping a background task without losing the caller's own cancellation.

The usual way to stop a task, ``task.cancel()`` followed by ``await task`` under
``contextlib.suppress(asyncio.CancelledError)``, cannot tell the task's
CancelledError (expected: we asked for it) from the caller's own (someone is
cancelling *us* while we wait). It swallows both, so a caller cancelled during its
cleanup carries on as if nothing happened, and whoever cancelled it waits forever or
sees it return normally. :func:`cancel_and_wait` swallows only the first kind.
"""

from __future__ import annotations

import asyncio
from typing import Any

__all__ = ["cancel_and_wait"]


async def cancel_and_wait(*tasks: asyncio.Future[Any]) -> None:
    """Cancel ``tasks``, wait until each has ended, and keep the caller's cancellation.

    All tasks are cancelled first, so they wind down together, then awaited in turn.
    A task's CancelledError is swallowed; any other exception it ended with is raised,
    as a plain ``await`` would. CancelledError is raised when the caller itself was
    cancelled while waiting (its ``cancelling()`` count rose). That also covers a task
    that ignores its cancel and returns normally: asyncio then forgets the caller's
    cancel, which is raised here instead. A cancel the caller had already received
    before the call (cleanup in a ``finally`` of a cancelled task) is not raised again,
    so the rest of that cleanup still runs and the original CancelledError goes on.
    """
    for task in tasks:
        task.cancel()
    current = asyncio.current_task()
    before = current.cancelling() if current is not None else 0
    for task in tasks:
        try:
            await task
        except asyncio.CancelledError:
            if current is not None and current.cancelling() > before:
                raise
        else:
            if current is not None and current.cancelling() > before:
                raise asyncio.CancelledError
