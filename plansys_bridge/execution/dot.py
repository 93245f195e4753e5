"""The plan graph as Graphviz DOT, coloured by action state, with ordered sub-goals.

PlanSys2 publishes such a graph on ``dot_graph`` for monitoring; here each node is
an action (label: step, text, planned start and duration), each edge a dependency
(tooltip: why), and a second cluster lists the goal's atoms in the order the plan
achieves them, each linked to the action that achieves it.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from plansys_bridge.execution.plan_graph import PlanGraph
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.pddl.model import Atom

__all__ = ["STATUS_COLOURS", "IncrementalDot", "plan_graph_to_dot"]

STATUS_COLOURS: dict[ActionStatus, str] = {
    ActionStatus.NOT_EXECUTED: "white",
    ActionStatus.EXECUTING: "yellow",
    ActionStatus.SUCCEEDED: "palegreen",
    ActionStatus.FAILED: "tomato",
    ActionStatus.CANCELLED: "orange",
}


def _quote(text: str) -> str:
    """A DOT string: quotes and backslashes escaped, line breaks as DOT's ``\\n``.

    Escaping the backslash of a ``\\n`` already in ``text`` would show a literal
    backslash-n in the picture, so labels carry real newlines and only here become
    the escape Graphviz centres a line break for.
    """
    escaped = text.replace("\\", "\\\\").replace('"', '\\"')
    return '"' + escaped.replace("\r\n", "\n").replace("\n", "\\n") + '"'


def plan_graph_to_dot(
    graph: PlanGraph,
    statuses: Sequence[ActionStatus] | None = None,
    goal_atoms: Iterable[Atom] = (),
    *,
    name: str = "plan",
) -> str:
    """DOT text of ``graph``; ``statuses`` (one per step) colour the nodes."""
    dot = IncrementalDot(graph, goal_atoms, name=name)
    for i, status in enumerate(statuses or ()):
        dot.set_status(i, status)
    return dot.text()


class IncrementalDot:
    """The DOT text of one plan, kept between publications: edges and sub-goals are
    written once, and a status change rewrites only its node's line (the executor
    publishes the graph while the plan runs, and rewriting a large graph on every
    change made execution cost grow with the square of the plan's length)."""

    def __init__(self, graph: PlanGraph, goal_atoms: Iterable[Atom] = (), *, name: str = "plan"):
        self._graph = graph
        self._head = "\n".join(
            [
                f"digraph {_quote(name)} {{",
                "  rankdir=LR;",
                '  node [shape=box, style="rounded,filled"];',
                '  subgraph "cluster_plan" {',
                '    label="plan";',
            ]
        )
        self._nodes = [self._node(i, ActionStatus.NOT_EXECUTED) for i in range(len(graph.steps))]
        self._statuses = [ActionStatus.NOT_EXECUTED] * len(graph.steps)
        self._tail = _tail(graph, goal_atoms)
        self._text: str | None = None

    def _node(self, i: int, status: ActionStatus) -> str:
        step = self._graph.steps[i]
        label = f"{i}: {step.text}\n[{step.time:.3f}, {step.duration:.3f}] {status.name.lower()}"
        return f"    a{i} [label={_quote(label)}, fillcolor={STATUS_COLOURS[status]}];"

    def set_status(self, i: int, status: ActionStatus) -> None:
        if self._statuses[i] is not status:
            self._statuses[i] = status
            self._nodes[i] = self._node(i, status)
            self._text = None

    def text(self) -> str:
        if self._text is None:
            self._text = "\n".join((self._head, *self._nodes, self._tail))
        return self._text


def _tail(graph: PlanGraph, goal_atoms: Iterable[Atom]) -> str:
    lines = ["  }"]
    for src, dst, data in sorted(graph.graph.edges(data=True)):
        lines.append(f"  a{src} -> a{dst} [tooltip={_quote(str(data.get('reason', '')))}];")
    goals = graph.ordered_subgoals(goal_atoms)
    if goals:
        lines.append('  subgraph "cluster_goals" {')
        lines.append('    label="ordered sub-goals";')
        lines.append("    node [shape=ellipse, style=filled, fillcolor=lightblue];")
        for k, (atom, _step) in enumerate(goals):
            lines.append(f"    g{k} [label={_quote(f'{k + 1}. {atom}')}];")
        for k in range(len(goals) - 1):
            lines.append(f"    g{k} -> g{k + 1} [style=invis];")
        lines.append("  }")
        for k, (_atom, achiever) in enumerate(goals):
            if achiever is not None:
                lines.append(f"  a{achiever} -> g{k} [style=dashed, arrowhead=none];")
    lines.append("}")
    return "\n".join(lines) + "\n"
