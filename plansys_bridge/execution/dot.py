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

__all__ = ["STATUS_COLOURS", "plan_graph_to_dot"]

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
    lines = [
        f"digraph {_quote(name)} {{",
        "  rankdir=LR;",
        '  node [shape=box, style="rounded,filled"];',
    ]
    lines.append('  subgraph "cluster_plan" {')
    lines.append('    label="plan";')
    for i, step in enumerate(graph.steps):
        status = statuses[i] if statuses is not None else ActionStatus.NOT_EXECUTED
        label = f"{i}: {step.text}\n[{step.time:.3f}, {step.duration:.3f}] {status.name.lower()}"
        lines.append(f"    a{i} [label={_quote(label)}, fillcolor={STATUS_COLOURS[status]}];")
    lines.append("  }")
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
