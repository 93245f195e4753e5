"""Write a run's report folder: Gantt chart, plan graphs, summary.

``DIR/gantt.svg`` and ``DIR/gantt.png``, ``DIR/plan_graph.dot`` and
``DIR/plan_graph.svg`` (the last plan executed; earlier plans of a replanned run as
``plan_graph_1.dot/.svg``, ``plan_graph_2...``) and ``DIR/summary.json``.
"""

from __future__ import annotations

import json
from pathlib import Path

from plansys_bridge.report.model import ReportError, RunReport

__all__ = ["write_report"]


def write_report(report: RunReport, folder: str | Path, *, use_graphviz: bool = True) -> list[Path]:
    """Write every file of the report into ``folder`` (created); returns their paths."""
    from plansys_bridge.report.gantt import draw_gantt
    from plansys_bridge.report.graph import render_dot

    out = Path(folder)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ReportError(f"{out}: cannot create the report folder: {exc}") from exc
    written: list[Path] = []
    gantt = [out / "gantt.svg", out / "gantt.png"]
    draw_gantt(report, *gantt)
    written += gantt
    graphs = list(report.dots.values())
    layouts: list[str] = []
    for number, text in enumerate(graphs, start=1):
        stem = "plan_graph" if number == len(graphs) else f"plan_graph_{number}"
        dot = out / f"{stem}.dot"
        dot.write_text(text, encoding="utf-8")
        svg = out / f"{stem}.svg"
        layouts.append(render_dot(text, svg, use_graphviz=use_graphviz))
        written += [dot, svg]
    summary = report.summary() | {"plan_graph_layout": layouts[-1] if layouts else None}
    path = out / "summary.json"
    path.write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    written.append(path)
    return written
