"""SIGTERM stops a command the way Ctrl-C does.

``systemctl stop``, ``docker stop`` and ``kill`` send SIGTERM, whose default ends the
process on the spot: a mission's actions are not cancelled and its performers not
stopped (no zero-velocity command to a CAN base, no safe mode for a copter). While a
command runs, SIGTERM is handed to the SIGINT handler in force (asyncio's, which
cancels the mission so that it shuts down in order), and the command then ends with
``terminated`` and exit status 143 instead of 130. Only the first SIGTERM counts: a
supervisor or script sending it again does not interrupt the orderly stop.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType

__all__ = ["Termination", "sigterm_interrupts"]


class Termination:
    """Whether SIGTERM arrived while the command ran."""

    def __init__(self) -> None:
        self.received = False

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        if self.received:
            # already stopping in order (cancelling actions, making vehicles safe): a
            # repeated SIGTERM must not cut that short; SIGKILL still ends it at once
            return
        self.received = True
        handler = signal.getsignal(signal.SIGINT)
        if callable(handler):
            handler(signum, frame)  # asyncio's: cancel the main task; else KeyboardInterrupt
            return
        raise KeyboardInterrupt  # SIGINT ignored (a background job): stop anyway


@contextlib.contextmanager
def sigterm_interrupts() -> Iterator[Termination]:
    """Within the block SIGTERM acts as SIGINT; the previous handler comes back after."""
    termination = Termination()
    if threading.current_thread() is not threading.main_thread():
        yield termination
        return
    previous = signal.signal(signal.SIGTERM, termination)
    try:
        yield termination
    finally:
        signal.signal(signal.SIGTERM, previous)
