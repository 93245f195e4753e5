"""Live progress on a terminal: a table of the current plan's actions, redrawn in place.

One row per action: its state, a completion bar fed by the performers' FEEDBACK,
the performer that won its auction; under it the performers with their state and
the replans so far. Lines worth keeping (a failure, a replan, an event) are also
printed above the table, so the scrollback tells the story once the run is over.
Only for a TTY: logs and pipes get :class:`~plansys_bridge.monitoring.progress.ProgressLines`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from types import TracebackType
from typing import Any

from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.monitoring.watch import ActionView, MissionWatch, WatchEvent

__all__ = ["LiveView", "make_live_view"]

REFRESH_PER_SECOND = 8

_STYLE = {
    ActionStatus.NOT_EXECUTED: "dim",
    ActionStatus.EXECUTING: "yellow",
    ActionStatus.SUCCEEDED: "green",
    ActionStatus.FAILED: "bold red",
    ActionStatus.CANCELLED: "dark_orange",
}


class LiveView:
    """A watch listener drawing the run with rich (see module docs).

    Use as a context manager around the run; ``watch`` is the watch it listens to
    (set by :meth:`bind` when created before the watch).
    """

    def __init__(self, elapsed: Callable[[], float], title: str = "", console: Any = None) -> None:
        from rich.console import Console

        self.elapsed = elapsed
        self.title = title
        self.console = console if console is not None else Console()
        self.watch: MissionWatch | None = None
        self._live: Any = None
        self._next_render = 0.0

    def bind(self, watch: MissionWatch) -> None:
        self.watch = watch

    def __enter__(self) -> LiveView:
        from rich.live import Live

        self._live = Live(
            self.render(),
            console=self.console,
            refresh_per_second=REFRESH_PER_SECOND,
            transient=False,
        )
        self._live.__enter__()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._live is not None:
            self._live.update(self.render())
            self._live.__exit__(exc_type, exc, tb)
            self._live = None

    def say(self, text: str) -> None:
        """Print a line above the table."""
        self.console.print(text, markup=False, highlight=False)

    def __call__(self, event: WatchEvent) -> None:
        t = f"[{self.elapsed():8.1f}]"
        line = None
        if event.kind == "plan" and event.plan is not None and event.plan.replan:
            line = f"{t} replanned (plan {event.plan.number + 1}, {len(event.plan.items)} actions)"
        elif event.kind == "status" and event.action is not None:
            a = event.action
            if a.status in (ActionStatus.FAILED, ActionStatus.CANCELLED):
                line = f"{t} {a.status.name:<9} {a.text} - {a.message}"
        if self._live is not None:
            # The table is rebuilt at most at the refresh rate (a virtual-clock run
            # sends thousands of events a second), and drawn at once before a line
            # is printed above it, so the scrollback shows the table of that moment.
            now = time.monotonic()
            if line is not None or now >= self._next_render:
                self._next_render = now + 1.0 / REFRESH_PER_SECOND
                self._live.update(self.render(), refresh=line is not None)
        if line is not None:
            self.say(line)

    def render(self) -> Any:
        from rich.console import Group
        from rich.progress_bar import ProgressBar
        from rich.table import Table
        from rich.text import Text

        watch = self.watch
        plan = watch.plans[-1] if watch is not None and watch.plans else None
        heading = f"{self.title}  t={self.elapsed():.1f} s"
        if plan is not None:
            heading += f"  plan {plan.number + 1} ({len(plan.actions)} actions)"
        table = Table(title=heading, title_justify="left", expand=False)
        table.add_column("#", justify="right")
        table.add_column("action")
        table.add_column("state")
        table.add_column("done", width=22)
        table.add_column("performer")
        for i, view in enumerate(plan.actions if plan is not None else []):
            table.add_row(
                str(i),
                view.text,
                Text(view.status.name.lower(), style=_STYLE[view.status]),
                _bar(view, ProgressBar),
                view.performer + (f" ({view.bids} bids)" if view.bids > 1 else ""),
            )
        parts: list[Any] = [table]
        if watch is not None and watch.performers:
            performers = "  ".join(
                f"{p.name}: {p.state.name.lower()}"
                for p in sorted(watch.performers.values(), key=lambda p: p.name)
            )
            parts.append(Text(f"performers  {performers}", style="cyan"))
        return Group(*parts)


def _bar(view: ActionView, bar: Any) -> Any:
    from rich.table import Table

    done = 1.0 if view.status == ActionStatus.SUCCEEDED else max(0.0, min(1.0, view.completion))
    grid = Table.grid(padding=(0, 1))
    grid.add_row(bar(total=1.0, completed=done, width=14), f"{100 * done:3.0f} %")
    return grid


def make_live_view(elapsed: Callable[[], float], title: str) -> LiveView | None:
    """The live table, or None when rich is not installed (plain lines then)."""
    try:
        return LiveView(elapsed, title=title)
    except ImportError:
        return None
