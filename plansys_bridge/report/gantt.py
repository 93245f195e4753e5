"""The Gantt chart of a run: planned against executed, one row per performer.

Each performer gets a row; in it, every action it ran shows twice: a hollow bar
where the plan put it (its plan's start plus the planned time) and, just under,
a filled bar for when it actually ran, coloured by how it ended. A cross marks each
failure, a dashed line each replan. Actions no performer took (never started,
halted before their auction) go in a last row, planned bars only. Drawn with
matplotlib's object API (no pyplot state), so it is safe in any process.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from plansys_bridge.report.model import ActionRow, RunReport

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["STATUS_COLOURS", "draw_gantt"]

STATUS_COLOURS = {
    "SUCCEEDED": "#59a14f",
    "FAILED": "#e15759",
    "CANCELLED": "#f28e2b",
    "EXECUTING": "#edc948",
    "NOT_EXECUTED": "#bab0ac",
}
UNASSIGNED = "not executed"


def _rows(report: RunReport) -> tuple[list[str], dict[int, int]]:
    """Row labels, and the row of each action (by index in ``report.actions``).

    Actions without a performer are packed into as few rows as keep them from
    overlapping (a replan can leave many planned-only actions at the same times).
    """
    rows = report.performers
    where = {i: rows.index(a.performer) for i, a in enumerate(report.actions) if a.performer}
    lanes: list[float] = []
    for i, a in sorted(
        ((i, a) for i, a in enumerate(report.actions) if not a.performer),
        key=lambda item: item[1].planned_start,
    ):
        lane = next((k for k, free in enumerate(lanes) if free <= a.planned_start + 1e-6), None)
        if lane is None:
            lane = len(lanes)
            lanes.append(0.0)
            rows.append(UNASSIGNED if lane == 0 else "")
        lanes[lane] = a.planned_end
        where[i] = len(rows) - len(lanes) + lane
    return rows, where


def draw_gantt(report: RunReport, *paths: Path) -> None:
    """Draw the chart to each of ``paths`` (the format follows the suffix: svg, png)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    rows, where = _rows(report)
    horizon = max(
        [report.total_time, *(a.planned_end for a in report.actions)]
        + [a.end for a in report.actions if a.end is not None]
        + [1.0]
    )
    fig = Figure(figsize=(max(8.0, min(24.0, 6 + horizon / 8)), 1.6 + 0.75 * max(1, len(rows))))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for i, action in enumerate(report.actions):
        _draw_action(ax, action, where[i])
    for number, when in enumerate(report.replans, start=2):
        ax.axvline(when, color="#7a5195", linestyle="--", linewidth=1.2)
        ax.text(when, -0.55, f" replan: plan {number}", color="#7a5195", fontsize=8, va="bottom")
    ax.set_yticks(range(len(rows)), rows)
    ax.set_ylim(len(rows) - 0.4, -0.7)
    ax.set_xlim(0, horizon * 1.02)
    ax.set_xlabel("mission time (s)")
    ax.grid(axis="x", color="#dddddd", linewidth=0.6)
    ax.set_axisbelow(True)
    outcome = "succeeded" if report.success else report.status
    ax.set_title(f"{report.name}: {outcome}, {report.total_time:.1f} s", fontsize=11)
    handles = [
        Patch(facecolor="none", edgecolor="#555555", hatch="///", label="planned"),
        *(
            Patch(facecolor=STATUS_COLOURS[s], label=s.lower().replace("_", " "))
            for s in ("SUCCEEDED", "FAILED", "CANCELLED")
        ),
        Line2D([], [], color="#e15759", marker="x", linestyle="", label="failure"),
        Line2D([], [], color="#7a5195", linestyle="--", label="replan"),
    ]
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.12),
        ncol=6,
        fontsize=8,
        frameon=False,
    )
    fig.tight_layout()
    save(fig, *paths)


def save(fig: Figure, *paths: Path) -> None:
    """Save ``fig`` to each path; SVG text stays text (searchable, selectable)."""
    from matplotlib import rc_context

    with rc_context({"svg.fonttype": "none"}):
        for path in paths:
            fig.savefig(path, dpi=110)


def _draw_action(ax: Axes, action: ActionRow, y: int) -> None:
    planned = action.planned_end - action.planned_start
    ax.broken_barh(
        [(action.planned_start, max(planned, 0.05))],
        (y - 0.38, 0.34),
        facecolors="none",
        edgecolors="#555555",
        hatch="///",
        linewidth=0.6,
    )
    if action.start is None:
        ax.text(
            action.planned_start + 0.1,
            y - 0.21,
            action.text.strip("()").split()[0],
            fontsize=6,
            color="#555555",
            va="center",
            clip_on=True,
        )
        return
    end = action.end if action.end is not None else action.start
    colour = STATUS_COLOURS.get(action.status, "#bab0ac")
    ax.broken_barh(
        [(action.start, max(end - action.start, 0.05))],
        (y + 0.0, 0.36),
        facecolors=colour,
        edgecolors="#333333",
        linewidth=0.5,
    )
    label = action.text.strip("()").split()[0]
    ax.text(action.start + 0.1, y + 0.18, label, fontsize=7, va="center", clip_on=True)
    if action.status == "FAILED":
        ax.plot([end], [y + 0.18], marker="x", color="#e15759", markersize=10, markeredgewidth=2.5)
