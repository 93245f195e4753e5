"""Which branches of a running plan a tick steps, and what wakes the others.

A branch is *active* (ticked), *parked* (its wait for predecessors found one
missing: woken when that happening takes place) or *resting* (a standard branch
whose performer works: woken when the performer ends, a deadline of its own passes
or the knowledge its over-all requirement reads changes). :class:`BranchWakeups`
keeps these sets and the tables that find the branches an event wakes, so a tick
costs what happened, not the size of the plan; :class:`PlanContext
<plansys_bridge.execution.plan_context.PlanContext>` is one.
"""

from __future__ import annotations

import asyncio
import heapq
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

from plansys_bridge.execution.action_runtime import ActionRuntime
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.pddl.model import Atom, Condition, FluentRef
from plansys_bridge.pddl.walkers import Collector
from plansys_bridge.planning.orderings import START, Point
from plansys_bridge.planning.plan_graph import PlanGraph

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import KnowledgeChange

__all__ = ["BranchWakeups"]

_get_ident = threading.get_ident


class _Reads(Collector):
    """Predicate and function names a condition reads; ``derived`` is set when it
    reads a derived predicate (whose inputs are not named in the condition)."""

    kinds = ("condition", "expression")

    def __init__(self, derived: frozenset[str]) -> None:
        self.derived_names = derived
        self.names: set[str] = set()
        self.derived = False

    def walk_atom(self, node: Atom) -> None:
        self.names.add(node.predicate)
        self.derived = self.derived or node.predicate in self.derived_names

    def walk_fluent_ref(self, node: FluentRef) -> None:
        self.names.add(node.name)


class BranchWakeups:
    """The active, parked and resting branches of one plan and their wake-ups (see
    module docs); the plan's context builds on it."""

    actions: list[ActionRuntime]
    evaluator: Evaluator

    def __init__(self, graph: PlanGraph) -> None:
        """Set up for ``graph``'s plan once ``actions`` holds its runtimes."""
        self.start_waits = graph.start_waits
        self.end_waits = graph.end_waits
        """Per action, the happenings its start and its end wait for (the graph's)."""
        self.active: set[int] = set(graph.roots())
        """Branches worth ticking: not parked waiting for a predecessor."""
        self._on_start: dict[int, list[int]] = {}
        self._on_end: dict[int, list[int]] = {}
        """For each action, the standard branches parked until it starts (ends) or
        stops: each is woken by the one happening it waits for, not by every move of
        every predecessor (see :meth:`park_on`)."""
        self._on_move: dict[int, list[int]] = {}
        """For each action, the template branches waiting on it: any move of it
        wakes them (a template's subtree may do more than wait while parked)."""
        self._first_move: dict[int, list[int]] = {}
        self.touched: list[int] = []
        """Standard branches not yet ticked one of whose predecessors moved since the
        last tick (filled from ``_first_move`` at each action's first move). Woken
        at every move of a predecessor, such a branch was ticked and found waiting,
        and py_trees' status of it was RUNNING from then on, which decides whether a
        cancel or a halt stops it: the tree gives it that status at its next tick
        instead (:meth:`PlanRoot.tick_once
        <plansys_bridge.execution.tree_builder.PlanRoot.tick_once>`)."""
        self.resting: set[int] = set()
        """Branches whose performer works and that nothing has touched since."""
        self._reads: dict[int, frozenset[str] | None] = {}
        self._reads_of: dict[int, tuple[Condition, frozenset[str] | None]] = {}
        self._derived: frozenset[str] | None = None
        self._readers: dict[str, set[int]] = {}
        """For each name some resting branch's over-all reads, those branches: a
        change then finds the branches it wakes by its names, whatever the number
        of resting branches."""
        self._deadlines: list[tuple[float, int]] = []
        """(mission time, index of the action to wake or -1) as a heap."""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._loop_thread = _get_ident()

    # ------------------------------------------------------------ time and wake-ups

    def now(self) -> float:
        """Mission time (the plan's context reads its clock)."""
        raise NotImplementedError

    def wake(self) -> None:  # replaced per instance by bind_wake's function
        """Ask for a tick as soon as possible (safe from the loop's thread only)."""

    def bind_wake(
        self, wake: Callable[[], None], loop: asyncio.AbstractEventLoop | None = None
    ) -> None:
        """Make ``wake`` what :meth:`wake` calls (itself, not through a method that
        forwards: about two wake-ups per action), and ``loop`` the loop whose thread
        :meth:`knowledge_changed` runs on (a change made in another thread is handed
        over to it)."""
        self.wake = wake  # type: ignore[method-assign]
        if loop is not None:
            self._loop = loop
            self._loop_thread = _get_ident()

    def schedule(self, deadline: float, owner: int | None = None) -> None:
        """Ask for a tick at mission time ``deadline``; a resting ``owner`` (action
        index) is woken for it. Only the standard branches rest, and only their own
        deadlines (an overrun) concern them, so a deadline passing wakes its owner,
        not every resting branch (a plan with an at-start timeout per action would
        otherwise tick every running action each time one of them passes)."""
        heapq.heappush(self._deadlines, (deadline, -1 if owner is None else owner))

    def next_deadline(self) -> float | None:
        """The earliest deadline not yet taken by :meth:`pass_deadlines`."""
        return self._deadlines[0][0] if self._deadlines else None

    def pass_deadlines(self) -> None:
        """Drop the deadlines that have come, waking their resting owners."""
        now = self.now()
        while self._deadlines and self._deadlines[0][0] <= now:
            _deadline, owner = heapq.heappop(self._deadlines)
            if owner >= 0:
                self.resume(owner)

    # ------------------------------------------------------------ which branches to tick

    def activate(self, index: int) -> None:
        if not self.actions[index].finished:
            self.active.add(index)

    def park(self, index: int) -> None:
        """Stop ticking a branch until one of its predecessors moves on."""
        self.active.discard(index)

    def park_on(self, rt: ActionRuntime, other: int, point: Point) -> None:
        """Stop ticking ``rt``'s branch until action ``other`` reaches ``point`` or
        stops (what its wait for predecessors found missing). A standard branch is
        then woken by that happening alone: waking it on every move of every
        predecessor cost a tick that found it still waiting about every other
        action. A template's branch is woken by any move of the actions it waits
        on, as before (its subtree may hold more than the wait)."""
        index = rt.index
        self.active.discard(index)
        if rt.may_rest:
            waiting = self._on_start if point == START else self._on_end
            found = waiting.get(other)
            if found is None:
                waiting[other] = [index]
            else:
                found.append(index)

    def park_waiting(self) -> None:
        """Park each branch that cannot start at once, before the first tick: a
        standard branch until the first happening its start waits for (its wait
        parks it on the next one if that is not all), a template's until any of
        the actions it waits on moves. Called once the branches are built (they
        say which are standard: ``may_rest``)."""
        actions, start_waits = self.actions, self.start_waits
        for rt, waits in zip(actions, start_waits, strict=True):
            if not waits:
                continue
            if rt.may_rest:
                other, point = waits[0]
                waiting = self._on_start if point == START else self._on_end
                waiting.setdefault(other, []).append(rt.index)
        for index, (rt, start, end) in enumerate(
            zip(actions, start_waits, self.end_waits, strict=True)
        ):
            if rt.may_rest and not start:
                continue  # ticked from the first tick on
            table = self._first_move if rt.may_rest else self._on_move
            for other, _point in (*start, *end):
                found = table.get(other)
                if found is None:
                    table[other] = [index]
                elif found[-1] != index:  # once per action it waits on
                    found.append(index)

    def _happened(self, index: int, woken: list[int] | None) -> None:
        """Action ``index`` moved: activate the branches parked on it (``woken``,
        those the happening concerns) and the template branches waiting on it, and
        on its first move list the standard branches it touches (``touched``)."""
        first = self._first_move.pop(index, None)
        if first is not None:
            self.touched.extend(first)
        actions, active = self.actions, self.active
        for waiting in (woken, self._on_move.get(index)):
            for i in waiting or ():
                if not actions[i].finished:
                    active.add(i)

    def rest(self, rt: ActionRuntime) -> None:
        """Stop ticking a standard branch whose performer is at work until the
        performer ends (:meth:`resume`), a deadline passes or the knowledge its
        over-all requirement reads changes (:meth:`knowledge_changed`)."""
        if not rt.may_rest:
            return
        index = rt.index
        if index in self.resting:
            self.active.discard(index)
            return
        # the names read, as _over_all_reads finds them, without its call per action
        cond = rt.ground.over_all
        known = self._reads_of.get(id(cond))
        if known is None or known[0] is not cond:
            known = self._learn_reads(cond)
        reads = known[1]
        self._reads[index] = reads
        if reads is None:
            return
        self.active.discard(index)
        self.resting.add(index)
        readers = self._readers
        for name in reads:
            found = readers.get(name)
            if found is None:
                readers[name] = {index}
            else:
                found.add(index)

    def resume(self, index: int) -> None:
        if index in self.resting:
            # _stop_resting() and activate(), inlined: once per executed action
            self.resting.discard(index)
            readers = self._readers
            for name in self._reads[index] or ():
                found = readers[name]
                found.discard(index)
                if not found:
                    del readers[name]
            if not self.actions[index].finished:
                self.active.add(index)

    def _stop_resting(self, index: int) -> None:
        if index not in self.resting:
            return
        self.resting.discard(index)
        for name in self._reads[index] or ():
            readers = self._readers[name]
            readers.discard(index)
            if not readers:
                del self._readers[name]

    def knowledge_changed(self, change: KnowledgeChange) -> None:
        """The executor's subscriber to the knowledge: give a tick to the resting
        branches whose over-all requirement reads something ``change`` touched (all
        of them when objects came or went), then wake the executor. A change made
        in another thread than the loop's is handed over to the loop."""
        if _get_ident() != self._loop_thread and self._loop is not None:
            self._loop.call_soon_threadsafe(self.knowledge_changed, change)
            return
        if self.resting:
            if change.added_instances or change.removed_instances:
                woken = set(self.resting)
            else:
                # Plain loops over the change (a few facts), not over the branches.
                readers = self._readers
                woken = set()
                for facts in (change.added_facts, change.removed_facts):
                    for atom in facts:
                        found = readers.get(atom.predicate)
                        if found:
                            woken.update(found)
                for keys in (change.changed_fluents, change.removed_fluents):
                    for key in keys:
                        found = readers.get(key[0])
                        if found:
                            woken.update(found)
            for index in woken:
                self.resume(index)
        self.wake()

    def _over_all_reads(self, rt: ActionRuntime) -> frozenset[str] | None:
        """Names the action's over-all requirement reads; None when that cannot be
        told from the condition (a derived predicate)."""
        index = rt.index
        if index not in self._reads:
            cond = rt.ground.over_all
            known = self._reads_of.get(id(cond))
            if known is None or known[0] is not cond:
                known = self._learn_reads(cond)
            self._reads[index] = known[1]
        return self._reads[index]

    def _learn_reads(self, cond: Condition) -> tuple[Condition, frozenset[str] | None]:
        """Work out the names ``cond`` reads. A plan repeats its ground actions: the
        names are worked out once per condition object (kept alive by the entry, so
        its id is not reused)."""
        if self._derived is None:
            self._derived = frozenset(d.head.name for d in self.evaluator.domain.derived)
        walker = _Reads(self._derived)
        walker.walk(cond)
        known = (cond, None if walker.derived else frozenset(walker.names))
        self._reads_of[id(cond)] = known
        return known
