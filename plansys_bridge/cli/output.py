"""Standard output when it is a pipe: lines as they happen, and a reader that leaves.

``plansys-bridge run m.yaml | tee run.log`` should show each action as it starts,
so progress lines are flushed one by one. ``... | head`` closes the pipe early; the
command must not answer with a BrokenPipeError traceback (nor, for a mission, stop
its robots half-way because nobody reads any more): the rest of the output goes
to /dev/null.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys

__all__ = ["drop_stdout", "say"]


def drop_stdout() -> None:
    """The reader of stdout went away: send everything still to come to /dev/null."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        # the same file descriptor, so even the interpreter's last flush finds a reader
        os.dup2(devnull, sys.stdout.fileno())
    except (AttributeError, OSError, io.UnsupportedOperation):
        sys.stdout = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115 (lives on)
    finally:
        os.close(devnull)


def say(text: str) -> None:
    """Print one line at once; nothing, without an error, once the reader has gone."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        drop_stdout()
        with contextlib.suppress(BrokenPipeError):
            sys.stdout.flush()
