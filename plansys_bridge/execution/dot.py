"""The plan graph as Graphviz DOT, coloured by action state, with ordered sub-goals.

PlanSys2 publishes such a graph on ``dot_graph`` for monitoring; here each node is
an action (label: step, text, planned start and duration, state), each edge a
dependency (tooltip: why), and a second cluster lists the goal's atoms in the order
the plan achieves them, each linked to the action that achieves it.

pydot writes it: the graph, its clusters and defaults as pydot objects, and the
per-action statements (a node, an edge: thousands on a large plan, rewritten as
actions change state) in pydot's format with pydot's quoting, without building an
object for each (that cost seven times as much on a 1,000-action plan). pydot's
quoting turns a label's line breaks into DOT's ``\\n`` (the escape Graphviz breaks
a line at), so labels render on two lines, never with a literal backslash-n.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from typing import Any

import pydot

from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.pddl.model import Atom
from plansys_bridge.planning.plan_graph import PlanGraph

__all__ = ["STATUS_COLOURS", "IncrementalDot", "plan_graph_to_dot"]

STATUS_COLOURS: dict[ActionStatus, str] = {
    ActionStatus.NOT_EXECUTED: "white",
    ActionStatus.EXECUTING: "yellow",
    ActionStatus.SUCCEEDED: "palegreen",
    ActionStatus.FAILED: "tomato",
    ActionStatus.CANCELLED: "orange",
}


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
    written once, and a status change rewrites only its node's statement (the
    executor publishes the graph while the plan runs, and writing a large graph
    whole on every change made execution cost grow with the square of the plan's
    length). The node statements are joined in blocks of ``_BLOCK``, and a change
    rejoins only its block, so a publication joins a few blocks, not every node."""

    def __init__(self, graph: PlanGraph, goal_atoms: Iterable[Atom] = (), *, name: str = "plan"):
        self._graph = graph
        self._root = pydot.Dot(_text(name), graph_type="digraph", rankdir="LR")
        self._root.set_node_defaults(shape="box", style="rounded,filled")
        self._head = _opening(self._root) + _opening(pydot.Cluster("plan", label="plan"))
        # each node's label up to its state, quoted as pydot quotes (the quoting works
        # character by character, so a quoted prefix and a quoted state join into the
        # quoted label): a state change only joins three strings
        heads = _quoted_inner(
            [
                f"{i}: {step.text}\n[{step.time:.3f}, {step.duration:.3f}] "
                for i, step in enumerate(graph.steps)
            ]
        )
        self._labels = [f'a{i} [label="{head}' for i, head in enumerate(heads)]
        tail = _status_tail(ActionStatus.NOT_EXECUTED)
        self._nodes = [label + tail for label in self._labels]
        self._statuses = [ActionStatus.NOT_EXECUTED] * len(graph.steps)
        self._tail = "}\n" + self._dependencies() + self._subgoals(goal_atoms) + "}\n"
        self._blocks = [
            "".join(self._nodes[b : b + _BLOCK]) for b in range(0, len(self._nodes), _BLOCK)
        ]
        self._dirty: set[int] = set()
        self._text: str | None = None

    def _node(self, i: int, status: ActionStatus) -> str:
        """As ``_statement(f"a{i}", label=..., fillcolor=...)`` writes it (a test
        compares the two)."""
        return self._labels[i] + _status_tail(status)

    def set_status(self, i: int, status: ActionStatus) -> None:
        if self._statuses[i] is not status:
            self._statuses[i] = status
            self._nodes[i] = self._labels[i] + _status_tail(status)  # _node(), inlined
            self._dirty.add(i // _BLOCK)
            self._text = None

    def text(self) -> str:
        if self._text is None:
            for b in self._dirty:
                self._blocks[b] = "".join(self._nodes[b * _BLOCK : (b + 1) * _BLOCK])
            self._dirty.clear()
            self._text = "".join((self._head, *self._blocks, self._tail))
        return self._text

    def _dependencies(self) -> str:
        edges = list(self._graph.edge_reasons())
        tips = _quoted_inner([reason for _, _, reason in edges])
        return "".join(
            [
                f'a{src} -> a{dst} [tooltip="{tip}"];\n'
                for (src, dst, _), tip in zip(edges, tips, strict=True)
            ]
        )

    def _subgoals(self, goal_atoms: Iterable[Atom]) -> str:
        goals = self._graph.ordered_subgoals(goal_atoms)
        if not goals:
            return ""
        cluster = pydot.Cluster("goals", label="ordered sub-goals")
        cluster.set_node_defaults(shape="ellipse", style="filled", fillcolor="lightblue")
        for k, (atom, _step) in enumerate(goals):
            cluster.add_node(pydot.Node(f"g{k}", label=_text(f"{k + 1}. {atom}")))
        for k in range(len(goals) - 1):
            cluster.add_edge(pydot.Edge(f"g{k}", f"g{k + 1}", style="invis"))
        cluster.set_parent_graph(self._root)  # its edges too are written "->"
        links = "".join(
            _statement(f"a{achiever} -> g{k}", style="dashed", arrowhead="none")
            for k, (_atom, achiever) in enumerate(goals)
            if achiever is not None
        )
        return str(cluster.to_string()) + links


_BLOCK = 64
"""Node statements per cached block of :class:`IncrementalDot`."""


def _statement(target: str, **attrs: str) -> str:
    """A node or edge statement as pydot writes one (``a1 [label="...", fillcolor=white];``);
    ``target`` is made of our own ids. Free text (labels, tooltips) is always quoted
    by pydot; the few other values (colours, styles) are quoted when DOT needs it,
    each decided once."""
    listed = ", ".join(
        f"{k}={pydot.make_quoted(_text(v)) if k in _FREE_TEXT else _value(v)}"
        for k, v in attrs.items()
    )
    return f"{target} [{listed}];\n"


_FREE_TEXT = frozenset({"label", "tooltip"})


def _quoted_inner(texts: list[str]) -> list[str]:
    """Each of ``texts`` as ``pydot.make_quoted(_text(t))`` writes it, without the
    quotes around it. Both work character by character (a ``\\r\\n`` pair aside,
    which a separator keeps apart), so the texts are joined with a NUL between them,
    quoted in one call and split again: a plan's thousands of labels and tooltips
    cost a few calls, not a few each. A text holding a NUL is quoted on its own."""
    joined = "\x00".join(texts)
    if joined.count("\x00") != max(len(texts) - 1, 0):
        return [str(pydot.make_quoted(_text(t)))[1:-1] for t in texts]
    if not texts:
        return []
    return str(pydot.make_quoted(_text(joined)))[1:-1].split("\x00")


@functools.cache
def _status_tail(status: ActionStatus) -> str:
    """The end of a node statement after its label's prefix: the state's name (still
    inside the label's quotes) and the fill colour of the state."""
    name = pydot.make_quoted(_text(status.name.lower()))[1:]
    return f"{name}, fillcolor={_value(STATUS_COLOURS[status])}];\n"


@functools.cache
def _value(value: str) -> str:
    return str(pydot.quote_attr_if_necessary(value))


def _text(text: str) -> str:
    """``text`` for pydot: pydot escapes quotes and line breaks, but Graphviz also
    reads a backslash as the start of an escape (``\\n``, ``\\l``, ``\\N``), so a
    backslash that is part of the text is doubled first, and ``\\r\\n`` kept one
    line break (pydot writes ``\\r`` as Graphviz's right-justified break)."""
    return text.replace("\\", "\\\\").replace("\r\n", "\n").replace("\r", "\n")


def _opening(graph: Any) -> str:
    """The statements pydot writes for ``graph`` (kind, name, attributes, defaults)
    without its closing brace, so nodes can be added after it one by one."""
    text = str(graph.to_string())
    assert text.endswith("}\n"), text
    return text[: -len("}\n")]
