"""The dependency graph of a plan: who must wait for whom, and why.

A temporal plan lists actions with start times, but the times are only the planner's
guess. What really matters is *why* an action sits where it does: it needs a fact
another action makes true (a causal link), or it would break a fact another action
relies on (a threat), or two actions change the same thing differently (conflicting
effects). This module recovers those reasons so the executor can start every action
as soon as what it really depends on is done, and never lets unsafe actions overlap.

Unlike PlanSys2's builder, every constraint is between *happenings* (an action's
start or end), not whole actions. Two ``load`` actions that only need each other's
at-start effects may run together (PlanSys2 #211 made the second wait for the
first's end); an at-end requirement makes the *end* wait, not the start; and an
over-all requirement protects the whole interval of the action that holds it.

How: the plan's happenings are simulated in plan order on the current knowledge.
Each ground atom and each numeric fluent is a variable with a history of accesses
(reads, adds, deletes, numeric changes). Accesses that do not commute (a read and a
later delete, an add and a delete, an assignment and anything) are ordered as in the
plan; a read gets a causal link from the latest earlier happening that set the value
it reads. Every edge points forward in plan order, so the graph is always acyclic.
The simulation also evaluates every condition exactly (with the knowledge
:class:`~plansys_bridge.knowledge.evaluation.Evaluator`), so :meth:`PlanGraph.check`
can name the action and the requirement a plan does not explain. Finally a
transitive reduction keeps only the edges a reader needs. The simulation itself is
:mod:`plansys_bridge.planning.graph_builder`.
"""

from __future__ import annotations

import gc
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from functools import cached_property
from typing import NamedTuple, TypeVar

import networkx as nx

from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Atom, Domain
from plansys_bridge.planning.graph_builder import GraphBuilder
from plansys_bridge.planning.happening_order import happening_order, transitive_reduction
from plansys_bridge.planning.orderings import (
    END,
    GROUND,
    START,
    Ordering,
    PlanGraphError,
    Point,
    UnexplainedRequirement,
)
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.requirement_text import condition_text, describe_unmet
from plansys_bridge.planning.step_edges import (
    Links,
    StepEdges,
    group_orderings,
    networkx_graph,
    sorted_pairs,
    waits_of,
)
from plansys_bridge.planning.var_history import VarHistory, subject_text

__all__ = [
    "END",
    "GROUND",
    "START",
    "Ordering",
    "PlanGraph",
    "PlanGraphError",
    "Point",
    "UnexplainedRequirement",
    "build_plan_graph",
    "condition_text",
    "describe_unmet",
]


# ---------------------------------------------------------------- the result


class PlanGraph:
    """The plan's dependency graph.

    :attr:`orderings` are the reduced orderings between happenings (what the
    executor waits for, see :meth:`waits`). ``graph`` (networkx ``DiGraph``) has
    one node per plan step index (attributes ``action`` text, ``time``,
    ``duration``) and an edge ``i -> j`` when some happening of ``j`` must wait for
    some happening of ``i``; edge attributes: ``reason`` (readable text),
    ``orderings`` (list of :class:`Ordering`) and ``points`` (set of
    ``(source_point, target_point)`` pairs). Edges are transitively reduced at the
    level of happenings.

    Made by :func:`build_plan_graph`, the orderings, the networkx graph and the
    edge texts are made on first use: the executor needs only the waits, and for
    a 1,000-action plan making the rest cost as much as finding the orderings.
    Made with ``orderings`` given, everything is read from them.
    """

    def __init__(
        self,
        plan: Plan,
        steps: tuple[PlanStep, ...],
        ground: tuple[GroundAction, ...],
        orderings: Iterable[Ordering] | None = None,
        unexplained: tuple[UnexplainedRequirement, ...] = (),
        achievers: Mapping[Atom, int] | None = None,
        final_state: State | None = None,
        *,
        links: Links[VarHistory] | None = None,
        order: Sequence[int] | None = None,
        happenings: Sequence[int] | None = None,
        later: _Later | None = None,
    ) -> None:
        self.plan = plan
        self.steps = steps
        self.ground = ground
        self.unexplained = unexplained
        if later is None:
            self.__dict__["achievers"] = achievers if achievers is not None else {}
            self.__dict__["final_state"] = final_state
        self._later = later
        self._links = links if orderings is None else None
        pairs: Sequence[tuple[int, int]]
        if self._links is None:
            self.__dict__["orderings"] = tuple(orderings or ())
            pairs = [
                (2 * o.source + (o.source_point == END), 2 * o.target + (o.target_point == END))
                for o in self.orderings
            ]
        else:
            pairs = self._links.pairs
        self._start_waits, self._end_waits = waits_of(pairs, len(steps))
        if order is not None:
            self.__dict__["_order"] = list(order)
        self._happenings = happenings

    @cached_property
    def achievers(self) -> Mapping[Atom, int]:
        """For every atom true at the end of the plan, the step whose effect last
        set it (made when first asked: the executor does not ask)."""
        assert self._later is not None  # set in __init__ otherwise
        return _acyclic(self._later.achievers)

    @cached_property
    def final_state(self) -> State | None:
        """The state the plan leads to, simulated from the knowledge it was built on
        (made when first asked, in one change from the simulation's last state)."""
        assert self._later is not None  # set in __init__ otherwise
        return _acyclic(self._later.final_state)

    @cached_property
    def _order(self) -> list[int]:
        """The steps in the order of their first happening."""
        happenings = self._happenings
        if happenings is None:
            happenings = happening_order(self.steps)
        return list(dict.fromkeys([h >> 1 for h in happenings]))

    @cached_property
    def orderings(self) -> tuple[Ordering, ...]:
        """The reduced orderings, sorted by the plan position of their target, then
        of their source."""
        assert self._links is not None  # set in __init__ otherwise
        return _acyclic(self._links.orderings)

    def check(self) -> None:
        """Raise :class:`PlanGraphError` (an ``ExecutionError``) naming each action and
        requirement not explained by the knowledge or an earlier action."""
        if self.unexplained:
            raise PlanGraphError(self.unexplained)

    def __len__(self) -> int:
        return len(self.steps)

    @cached_property
    def _step_edges(self) -> StepEdges:
        return group_orderings(self.orderings)

    @cached_property
    def graph(self) -> nx.DiGraph:
        return networkx_graph(self.steps, self._step_edges)

    def edge_reasons(self) -> Iterator[tuple[int, int, str]]:
        """``(source, target, reason)`` of every edge of :attr:`graph` in sorted order,
        without making the networkx graph or the orderings (the DOT view needs only
        these)."""
        if self._links is not None and "orderings" not in self.__dict__:
            return iter(_acyclic(self._links.edge_reasons))
        return iter(
            [
                (source, target, "; ".join(o.reason for o in os))
                for (source, target), (os, _points) in sorted(self._step_edges.items())
            ]
        )

    def waits(self, step: int, point: Point) -> tuple[tuple[int, Point], ...]:
        """The happenings of other steps that ``step``'s ``point`` must wait for."""
        return self._start_waits[step] if point == START else self._end_waits[step]

    def predecessors(self, step: int) -> list[int]:
        return list(self.graph.predecessors(step))

    def successors(self, step: int) -> list[int]:
        return list(self.graph.successors(step))

    @property
    def start_waits(self) -> Sequence[tuple[tuple[int, Point], ...]]:
        """Per step, what its start waits for: ``start_waits[i]`` is
        ``waits(i, START)`` (the same tuple), read without a call per action."""
        return self._start_waits

    @property
    def end_waits(self) -> Sequence[tuple[tuple[int, Point], ...]]:
        """Per step, what its end waits for (``waits(i, END)``)."""
        return self._end_waits

    def roots(self) -> list[int]:
        """Steps that can start at once."""
        return [i for i, w in enumerate(self._start_waits) if not w]

    def dependents(self) -> list[set[int]]:
        """Per step, the steps with a start or end wait on it: new sets, filled in
        the order the executor's own loop over :meth:`waits` fills them (by
        dependent step, start waits before end waits), so they are equal and
        iterate alike. Why: the executor needs them once per plan, and asking
        :meth:`waits` twice per step cost two calls per action."""
        found: list[set[int]] = [set() for _ in self._start_waits]
        for i, (start, end) in enumerate(zip(self._start_waits, self._end_waits, strict=True)):
            for j, _ in start:
                found[j].add(i)
            for j, _ in end:
                found[j].add(i)
        return found

    def ordered_subgoals(self, goal_atoms: Iterable[Atom]) -> list[tuple[Atom, int | None]]:
        """Goal atoms in the order the plan achieves them, each with its achieving step
        (``None``: already true in the knowledge and never touched)."""
        keyed: list[tuple[tuple[float, int], Atom, int | None]] = []
        for atom in goal_atoms:
            step = self.achievers.get(atom)
            if step is None:
                keyed.append(((-1.0, -1), atom, None))
            else:
                keyed.append(((self.steps[step].end, step), atom, step))
        keyed.sort(key=lambda t: (t[0], str(t[1])))
        return [(atom, step) for _, atom, step in keyed]

    def earliest_schedule(self, durations: Sequence[float] | None = None) -> list[float]:
        """Earliest start time of every step that respects the orderings, with the
        plan's durations (or ``durations``); used to reschedule a plan."""
        dur = list(durations) if durations is not None else [s.duration for s in self.steps]
        start = [0.0] * len(self.steps)
        incoming: dict[int, list[Ordering]] = {}
        for o in self.orderings:
            incoming.setdefault(o.target, []).append(o)
        for j in self._order:
            for o in incoming.get(j, ()):
                src = start[o.source] + (dur[o.source] if o.source_point == END else 0.0)
                need = src - (dur[j] if o.target_point == END else 0.0)
                start[j] = max(start[j], need)
        return start


# ---------------------------------------------------------------- building


class _Later(NamedTuple):
    """What a built graph makes only when asked (from the builder's tables)."""

    final_state: Callable[[], State]
    achievers: Callable[[], dict[Atom, int]]


def build_plan_graph(
    plan: Plan,
    domain: Domain,
    state: State,
    *,
    evaluator: Evaluator | None = None,
    reduce: bool = True,
) -> PlanGraph:
    """Build the dependency graph of ``plan`` from ``state`` (usually the knowledge).

    Actions are grounded with the knowledge :class:`Evaluator`; an unknown action
    name or a wrong argument list raises :class:`ExecutionError` naming the step.
    Unexplained requirements do not raise here: they are listed in
    ``PlanGraph.unexplained`` and :meth:`PlanGraph.check` raises them.
    """
    ev = evaluator if evaluator is not None else Evaluator(domain)
    return _acyclic(lambda: _build(plan, domain, state, ev, reduce))


_T = TypeVar("_T")


def _acyclic(make: Callable[[], _T]) -> _T:
    """``make()`` with the cyclic collector paused. Why: building the graph (and
    its texts) makes many small objects and frees none of them until it ends, and
    none of them form cycles: the collector would only walk them again and again
    (and the whole heap, in an executor that holds a large knowledge base)."""
    collecting = gc.isenabled()
    gc.disable()
    try:
        return make()
    finally:
        if collecting:
            gc.enable()


def _build(plan: Plan, domain: Domain, state: State, ev: Evaluator, reduce: bool) -> PlanGraph:
    builder = GraphBuilder(plan.steps, domain, state, ev)
    ground, moves = builder.ground()
    order = happening_order(builder.steps)
    builder.simulate(ground, moves, order)
    kept = transitive_reduction(order, builder.succ, builder.pos) if reduce else builder.edges
    achieved = builder.achieved
    return PlanGraph(
        plan=plan,
        steps=builder.steps,
        ground=ground,
        unexplained=tuple(builder.unexplained),
        links=Links(sorted_pairs(kept, order, builder.pos), builder.edges, subject_text),
        happenings=order,
        later=_Later(
            builder.final_state,
            lambda: {hist.var[1]: i for hist, i in achieved.items()},  # type: ignore[misc]
        ),
    )
