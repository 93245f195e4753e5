"""The terminal's read-eval-print loop, with line editing, history and completion.

On a terminal: readline editing, tab completion (:mod:`.completion`) and a history
kept across sessions in ``~/.plansys_bridge_history`` (the last 1,000 lines), and
Ctrl-C abandons the line being typed instead of ending the session. From a pipe
or a file: no prompt, no history, so ``plansys-bridge terminal d.pddl < commands``
gives clean output.
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path
from typing import Protocol, TextIO

from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.terminal.completion import install

__all__ = ["HISTORY_FILE", "LineRunner", "run_repl"]


class LineRunner(Protocol):
    """What the loop drives: the terminal (:class:`~.core.Terminal`) runs one line at
    a time, says when ``quit`` was typed, and names the knowledge to complete from."""

    finished: bool
    out: TextIO
    problem_expert: ProblemExpert

    def execute_line(self, line: str) -> str: ...


HISTORY_FILE = Path("~/.plansys_bridge_history")
HISTORY_LENGTH = 1000


def run_repl(terminal: LineRunner, inp: TextIO | None = None, prompt: str | None = None) -> int:
    """Read commands until ``quit`` or end of input; returns an exit code."""
    source = inp if inp is not None else sys.stdin
    interactive = source is sys.stdin and source.isatty()
    if prompt is None:
        prompt = "> " if source.isatty() else ""
    history = _History() if interactive else None
    if history is not None:
        history.load()
        install(terminal.problem_expert)
    try:
        while not terminal.finished:
            if interactive:
                try:
                    line = input(prompt)
                except EOFError:
                    break
                except KeyboardInterrupt:
                    terminal.out.write("\n")
                    continue
            else:
                if prompt:
                    terminal.out.write(prompt)
                    terminal.out.flush()
                line = source.readline()
                if not line:
                    break
            result = terminal.execute_line(line)
            if result:
                terminal.out.write(result + "\n")
                terminal.out.flush()
    finally:
        if history is not None:
            history.save()
    return 0


class _History:
    """readline's history, kept in a file between sessions (never an error)."""

    def __init__(self) -> None:
        self.path = HISTORY_FILE.expanduser()

    def load(self) -> None:
        with contextlib.suppress(ImportError, OSError):
            import readline

            readline.set_history_length(HISTORY_LENGTH)
            if self.path.exists():
                readline.read_history_file(self.path)

    def save(self) -> None:
        with contextlib.suppress(ImportError, OSError):
            import readline

            readline.write_history_file(self.path)
