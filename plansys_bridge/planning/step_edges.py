"""The orderings kept between happenings, grouped by the steps they join.

The builder (:mod:`plansys_bridge.planning.plan_graph`) finds orderings between
happenings; the executor waits on them per happening, while a reader (the DOT view,
the report, tests) sees one edge per pair of steps. Both are made here in one pass
over the kept orderings, and the networkx graph only when someone asks for it:
making it for a 1,000-action plan cost as much as finding the orderings.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from typing import TypeAlias, TypeVar

import networkx as nx

from plansys_bridge.planning.orderings import END, START, Kind, Ordering, Point
from plansys_bridge.planning.plan import PlanStep

__all__ = ["StepEdges", "Waits", "networkx_graph", "orderings_of"]

StepEdges: TypeAlias = dict[tuple[int, int], tuple[list[Ordering], set[tuple[Point, Point]]]]
"""(source step, target step) -> (its orderings in plan order, their point pairs)."""

Waits: TypeAlias = list[tuple[tuple[int, Point], ...]]
"""Per step, the (step, point) happenings one of its points waits for."""

_Subject = TypeVar("_Subject")

_POINTS: tuple[Point, Point] = (START, END)
"""A happening's point by its parity (happening ``2*i`` is step ``i``'s start)."""


def orderings_of(
    kept: Collection[tuple[int, int]],
    edges: Mapping[tuple[int, int], tuple[Kind, _Subject]],
    pos: Mapping[int, int],
    n: int,
    describe: Callable[[_Subject], str],
) -> tuple[list[Ordering], Waits, Waits, StepEdges]:
    """The orderings of the ``kept`` happening pairs, sorted by the plan position of
    their target then source, with each step's start and end waits and the edges
    between steps. ``edges`` gives each pair's kind and subject (written as text by
    ``describe``, for the kept pairs only), ``pos`` each happening's plan position,
    ``n`` the number of steps."""
    orderings: list[Ordering] = []
    start_waits: list[list[tuple[int, Point]]] = [[] for _ in range(n)]
    end_waits: list[list[tuple[int, Point]]] = [[] for _ in range(n)]
    steps: StepEdges = {}
    width = len(pos) + 1  # one integer sort key instead of a key function per pair
    for _, src, dst in sorted([(pos[dst] * width + pos[src], src, dst) for src, dst in kept]):
        kind, subject = edges[(src, dst)]
        source, target = src // 2, dst // 2
        source_point, target_point = _POINTS[src % 2], _POINTS[dst % 2]
        o = Ordering(source, source_point, target, target_point, kind, describe(subject))
        orderings.append(o)
        (end_waits if dst % 2 else start_waits)[target].append((source, source_point))
        found = steps.get((source, target))
        if found is None:
            steps[(source, target)] = ([o], {(source_point, target_point)})
        else:
            found[0].append(o)
            found[1].add((source_point, target_point))
    return orderings, [tuple(w) for w in start_waits], [tuple(w) for w in end_waits], steps


def networkx_graph(steps: Sequence[PlanStep], edges: StepEdges) -> nx.DiGraph:
    """One node per step (``action``, ``time``, ``duration``) and one edge per pair of
    steps (``reason``, ``orderings``, ``points``), added in bulk."""
    graph = nx.DiGraph()
    graph.add_nodes_from(
        (i, {"action": step.text, "time": step.time, "duration": step.duration})
        for i, step in enumerate(steps)
    )
    graph.add_edges_from(
        (
            source,
            target,
            {"reason": "; ".join(o.reason for o in os), "orderings": list(os), "points": set(pp)},
        )
        for (source, target), (os, pp) in edges.items()
    )
    return graph
