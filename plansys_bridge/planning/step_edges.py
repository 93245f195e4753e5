"""The orderings kept between happenings, and the views made of them on demand.

The builder (:mod:`plansys_bridge.planning.graph_builder`) finds orderings between
happenings; the executor waits on them per happening, while a reader (the DOT view,
the report, tests) sees one edge per pair of steps. The executor's waits are made
at once; the :class:`Ordering` objects, their texts, the step-level edges and the
networkx graph only when someone asks for them: for a 1,000-action plan making
them cost as much as finding the orderings, and an executor that publishes no
graph never reads them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Generic, TypeAlias, TypeVar

import networkx as nx

from plansys_bridge.planning.orderings import END, START, Kind, Ordering, Point, reason_text
from plansys_bridge.planning.plan import PlanStep

__all__ = [
    "Links",
    "StepEdges",
    "Waits",
    "group_orderings",
    "networkx_graph",
    "sorted_pairs",
    "waits_of",
]

StepEdges: TypeAlias = dict[tuple[int, int], tuple[list[Ordering], set[tuple[Point, Point]]]]
"""(source step, target step) -> (its orderings in plan order, their point pairs)."""

Waits: TypeAlias = list[tuple[tuple[int, Point], ...]]
"""Per step, the (step, point) happenings one of its points waits for."""

_Subject = TypeVar("_Subject")

_POINTS: tuple[Point, Point] = (START, END)
"""A happening's point by its parity (happening ``2*i`` is step ``i``'s start)."""


def sorted_pairs(
    kept: Iterable[tuple[int, int]], order: Sequence[int], pos: Sequence[int]
) -> list[tuple[int, int]]:
    """The ``kept`` happening pairs sorted by the plan position of their target,
    then of their source (``order`` lists the happenings by position, ``pos`` gives
    each one's): one integer sort key per pair, no key function."""
    width = len(order)
    keys = sorted([pos[dst] * width + pos[src] for src, dst in kept])
    return [(order[k % width], order[k // width]) for k in keys]


def waits_of(pairs: Iterable[tuple[int, int]], n: int) -> tuple[Waits, Waits]:
    """Each of the ``n`` steps' start and end waits, in the order of ``pairs``.

    The builder's pairs come grouped by target (sorted by its plan position), so a
    target's waits are gathered in one run and made a tuple once; a target seen
    again later (orderings given in another order) gets the run added to its
    tuple. A step with no waits shares the empty tuple."""
    waits: list[tuple[tuple[int, Point], ...]] = [()] * (2 * n)
    points = _POINTS
    run: list[tuple[int, Point]] = []
    target = -1
    for src, dst in pairs:
        if dst != target:
            if run:
                waits[target] += tuple(run)
            target = dst
            run = [(src >> 1, points[src & 1])]
        else:
            run.append((src >> 1, points[src & 1]))
    if run:
        waits[target] += tuple(run)
    return waits[0::2], waits[1::2]


class Links(Generic[_Subject]):
    """The builder's kept happening pairs in ordering order, each with its kind and
    subject in ``edges``; ``describe`` writes a subject as the orderings do."""

    def __init__(
        self,
        pairs: Sequence[tuple[int, int]],
        edges: Mapping[tuple[int, int], tuple[Kind, _Subject]],
        describe: Callable[[_Subject], str],
    ) -> None:
        self.pairs = pairs
        self.edges = edges
        self.describe = describe

    def orderings(self) -> tuple[Ordering, ...]:
        edges, describe = self.edges, self.describe
        out: list[Ordering] = []
        for src, dst in self.pairs:
            kind, subject = edges[(src, dst)]
            out.append(
                Ordering(
                    src >> 1, _POINTS[src & 1], dst >> 1, _POINTS[dst & 1], kind, describe(subject)
                )
            )
        return tuple(out)

    def edge_reasons(self) -> list[tuple[int, int, str]]:
        """``(source, target, reason)`` per pair of steps, sorted, as
        :func:`group_orderings` and the orderings' reasons would give them; each
        distinct reason is written once."""
        edges, describe = self.edges, self.describe
        written: dict[tuple[int, int, Kind, _Subject], str] = {}
        groups: dict[tuple[int, int], list[str]] = {}
        for src, dst in self.pairs:
            kind, subject = edges[(src, dst)]
            key = (src & 1, dst & 1, kind, subject)
            if key in written:
                reason = written[key]
            else:
                reason = written[key] = reason_text(
                    _POINTS[src & 1], _POINTS[dst & 1], kind, describe(subject)
                )
            pair = (src >> 1, dst >> 1)
            if pair in groups:
                groups[pair].append(reason)
            else:
                groups[pair] = [reason]
        return [(s, t, "; ".join(reasons)) for (s, t), reasons in sorted(groups.items())]


def group_orderings(orderings: Iterable[Ordering]) -> StepEdges:
    """The orderings grouped by the pair of steps they join, in their order."""
    steps: StepEdges = {}
    for o in orderings:
        found = steps.get((o.source, o.target))
        if found is None:
            steps[(o.source, o.target)] = ([o], {(o.source_point, o.target_point)})
        else:
            found[0].append(o)
            found[1].add((o.source_point, o.target_point))
    return steps


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
