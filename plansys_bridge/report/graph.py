"""The plan graph as a picture: Graphviz when installed, else a pure-Python layout.

The executor publishes the coloured plan graph as DOT text (``dot_graph``); this
turns one into SVG. With Graphviz's ``dot`` on ``PATH`` it does the layout (what a
PlanSys2 user gets from ``xdot``). Without it, pydot parses the same text and the
graph is laid out in layers: each action as far right as its longest chain of
dependencies (``rankdir=LR``), the ordered sub-goals in a column of their own, and
drawn with matplotlib; boxes keep the DOT's labels and fill colours.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from plansys_bridge.report.model import ReportError

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["DotGraphError", "render_dot"]

FONT_WIDTH_IN = 7 / 72 * 0.62
"""Width of one character of the 7-point labels, in inches (a DejaVu Sans average)."""


class DotGraphError(ReportError):
    """A DOT text that cannot be read or drawn."""


def render_dot(dot_text: str, svg: Path, *, use_graphviz: bool = True) -> str:
    """Write ``dot_text`` as SVG to ``svg``; returns which layout drew it
    (``"graphviz"`` or ``"python"``)."""
    exe = shutil.which("dot") if use_graphviz else None
    if exe is not None:
        try:
            subprocess.run(
                [exe, "-Tsvg", "-o", str(svg)],
                input=dot_text,
                text=True,
                check=True,
                capture_output=True,
                timeout=120,
            )
            return "graphviz"
        except (OSError, subprocess.SubprocessError):
            pass  # a broken Graphviz install: the pure-Python layout still works
    _python_layout(dot_text, svg)
    return "python"


@dataclass
class _Node:
    name: str
    label: str
    fill: str = "white"
    ellipse: bool = False
    cluster: str = ""


@dataclass
class _Graph:
    nodes: dict[str, _Node] = field(default_factory=dict)
    edges: list[tuple[str, str, bool]] = field(default_factory=list)
    """(source, target, dashed)."""


def _unquote(value: Any) -> str:
    text = str(value or "")
    if len(text) >= 2 and text[0] == text[-1] == '"':
        text = text[1:-1]
    return text.replace("\\n", "\n").replace('\\"', '"').replace("\\\\", "\\")


def _read(dot_text: str) -> _Graph:
    import pydot  # a dependency of the package (the executor writes DOT with it)

    parsed = pydot.graph_from_dot_data(dot_text)
    if not parsed:
        raise DotGraphError("not a DOT graph")
    graph = _Graph()

    def walk(g: Any, cluster: str, defaults: dict[str, str]) -> None:
        local = dict(defaults)
        for node in g.get_nodes():
            name = node.get_name().strip('"')
            attrs = node.get_attributes()
            if name == "node":
                local.update({k: _unquote(v) for k, v in attrs.items()})
                continue
            if name in ("graph", "edge"):
                continue
            merged = local | {k: _unquote(v) for k, v in attrs.items()}
            graph.nodes[name] = _Node(
                name,
                merged.get("label", name),
                merged.get("fillcolor", "white"),
                merged.get("shape", "box") == "ellipse",
                cluster,
            )
        for edge in g.get_edges():
            style = _unquote(edge.get_attributes().get("style", ""))
            if style != "invis":
                src = str(edge.get_source()).strip('"')
                dst = str(edge.get_destination()).strip('"')
                graph.edges.append((src, dst, style == "dashed"))
        for sub in g.get_subgraphs():
            walk(sub, sub.get_name().strip('"'), local)

    walk(parsed[0], "", {})
    return graph


def _layers(graph: _Graph) -> dict[str, tuple[int, int]]:
    """(column, row) of each node: actions by longest dependency chain, goals last."""
    import networkx as nx

    solid = nx.DiGraph()
    solid.add_nodes_from(n for n, node in graph.nodes.items() if not node.ellipse)
    solid.add_edges_from((s, d) for s, d, dashed in graph.edges if not dashed and s in solid)
    column: dict[str, int] = {}
    if nx.is_directed_acyclic_graph(solid):
        for node in nx.topological_sort(solid):
            preds = list(solid.predecessors(node))
            column[node] = 1 + max((column[p] for p in preds), default=-1)
    else:  # not a plan graph; keep it readable anyway
        column = {n: i for i, n in enumerate(solid)}
    goal_column = max(column.values(), default=-1) + 1
    for name, node in graph.nodes.items():
        if node.ellipse:
            column[name] = goal_column
    rows: dict[int, int] = {}
    where: dict[str, tuple[int, int]] = {}
    for name in graph.nodes:
        c = column[name]
        where[name] = (c, rows.get(c, 0))
        rows[c] = rows.get(c, 0) + 1
    return where


def _python_layout(dot_text: str, svg: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from plansys_bridge.report.gantt import save

    graph = _read(dot_text)
    where = _layers(graph)
    columns = 1 + max((c for c, _ in where.values()), default=0)
    rows = 1 + max((r for _, r in where.values()), default=0)
    # coordinates in inches: a column is as wide as the longest label line
    longest = max(
        (len(line) for node in graph.nodes.values() for line in node.label.splitlines()),
        default=10,
    )
    dx, dy = longest * FONT_WIDTH_IN + 0.9, 0.8
    fig = Figure(figsize=(max(3.0, columns * dx), max(1.0, rows * dy)))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_axis_off()
    ax.set_xlim(-dx / 2, columns * dx - dx / 2)
    ax.set_ylim(rows * dy - dy / 2, -dy / 2)
    centre = {name: (c * dx, r * dy) for name, (c, r) in where.items()}
    boxes = {name: _box(ax, node, centre[name]) for name, node in graph.nodes.items()}
    for src, dst, dashed in graph.edges:
        if src in boxes and dst in boxes:
            ax.annotate(
                "",
                xy=centre[dst],
                xytext=centre[src],
                arrowprops={
                    "arrowstyle": "-" if dashed else "-|>",
                    "linestyle": "--" if dashed else "-",
                    "color": "#555555",
                    "patchA": boxes[src],
                    "patchB": boxes[dst],
                    "shrinkA": 2,
                    "shrinkB": 2,
                },
            )
    save(fig, svg)


def _box(ax: Axes, node: _Node, at: tuple[float, float]) -> Any:
    text = ax.text(
        at[0],
        at[1],
        node.label,
        ha="center",
        va="center",
        fontsize=7,
        bbox={
            "boxstyle": "ellipse,pad=0.3" if node.ellipse else "round,pad=0.3",
            "facecolor": node.fill,
            "edgecolor": "#333333",
        },
    )
    return text.get_bbox_patch()
