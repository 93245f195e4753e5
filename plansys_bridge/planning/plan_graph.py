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
transitive reduction keeps only the edges a reader needs.
"""

from __future__ import annotations

import gc
from collections.abc import Collection, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TypeAlias

import networkx as nx

from plansys_bridge.errors import ExecutionError
from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import (
    Atom,
    Condition,
    Domain,
    Effect,
)
from plansys_bridge.planning.effect_access import (
    EffectAccess,
    Var,
    condition_vars,
    effect_access,
    reads_fixed,
    writes_fixed,
)
from plansys_bridge.planning.happening_order import (
    happening_order,
    transitive_reduction,
)
from plansys_bridge.planning.orderings import (
    END,
    GROUND,
    START,
    Kind,
    Ordering,
    PlanGraphError,
    Point,
    UnexplainedRequirement,
    When,
)
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.requirement_text import condition_text, describe_unmet
from plansys_bridge.planning.step_edges import StepEdges, networkx_graph, orderings_of
from plansys_bridge.planning.var_history import Access, VarHistory, subject_text

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

_Var: TypeAlias = Var


# ---------------------------------------------------------------- the result


@dataclass
class PlanGraph:
    """The plan's dependency graph.

    ``graph`` (networkx ``DiGraph``) has one node per plan step index (attributes
    ``action`` text, ``time``, ``duration``) and an edge ``i -> j`` when some
    happening of ``j`` must wait for some happening of ``i``; edge attributes:
    ``reason`` (readable text), ``orderings`` (list of :class:`Ordering`) and
    ``points`` (set of ``(source_point, target_point)`` pairs). Edges are
    transitively reduced at the level of happenings. It is made on first use: the
    executor needs only the orderings, and making a networkx graph of a
    1,000-action plan cost as much as finding its orderings.
    """

    plan: Plan
    steps: tuple[PlanStep, ...]
    ground: tuple[GroundAction, ...]
    orderings: tuple[Ordering, ...]
    """The reduced orderings (what the executor waits for)."""
    unexplained: tuple[UnexplainedRequirement, ...] = ()
    achievers: Mapping[Atom, int] = field(default_factory=dict)
    """For every atom true at the end of the plan, the step whose effect last set it."""
    final_state: State | None = None
    """The state the plan leads to, simulated from the knowledge it was built on."""

    def check(self) -> None:
        """Raise :class:`PlanGraphError` (an ``ExecutionError``) naming each action and
        requirement not explained by the knowledge or an earlier action."""
        if self.unexplained:
            raise PlanGraphError(self.unexplained)

    def __len__(self) -> int:
        return len(self.steps)

    @cached_property
    def graph(self) -> nx.DiGraph:
        return networkx_graph(self.steps, self._step_edges)

    def edge_reasons(self) -> Iterator[tuple[int, int, str]]:
        """``(source, target, reason)`` of every edge of :attr:`graph` in sorted order,
        without making the networkx graph (the DOT view needs only these)."""
        for (source, target), (os, _points) in sorted(self._step_edges.items()):
            yield source, target, "; ".join(o.reason for o in os)

    def waits(self, step: int, point: Point) -> tuple[tuple[int, Point], ...]:
        """The happenings of other steps that ``step``'s ``point`` must wait for."""
        table = self._start_waits if point == START else self._end_waits
        return table[step]

    def predecessors(self, step: int) -> list[int]:
        return list(self.graph.predecessors(step))

    def successors(self, step: int) -> list[int]:
        return list(self.graph.successors(step))

    def roots(self) -> list[int]:
        """Steps that can start at once."""
        return [i for i in range(len(self.steps)) if not self._start_waits[i]]

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

    # filled by the builder
    _start_waits: list[tuple[tuple[int, Point], ...]] = field(default_factory=list, repr=False)
    _end_waits: list[tuple[tuple[int, Point], ...]] = field(default_factory=list, repr=False)
    _order: list[int] = field(default_factory=list, repr=False)
    _step_edges: StepEdges = field(default_factory=dict, repr=False)


# ---------------------------------------------------------------- building


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
    # The build makes many small objects and frees none of them until it ends, and
    # none of them form cycles: the cyclic collector would only walk them again and
    # again (and the whole heap, in an executor that holds a large knowledge base).
    collecting = gc.isenabled()
    gc.disable()
    try:
        return _Builder(plan, domain, state, ev).build(reduce=reduce)
    finally:
        if collecting:
            gc.enable()


class _Builder:
    def __init__(self, plan: Plan, domain: Domain, state: State, ev: Evaluator) -> None:
        self.plan = plan
        self.domain = domain
        self.initial = state
        self.ev = ev
        self.steps = tuple(plan.steps)
        self.edges: dict[tuple[int, int], tuple[Kind, VarHistory]] = {}
        self.vars: dict[_Var, VarHistory] = {}
        self.unexplained: list[UnexplainedRequirement] = []
        self.achievers: dict[Atom, int] = {}
        # What a ground condition reads / an effect touches, by id, for those whose
        # answer is the same in every state (see effect_access.reads_fixed); the
        # ground actions are shared between repeated steps and outlive the build.
        self._fixed_reads: dict[int, tuple[VarHistory, ...] | None] = {}
        self._fixed_effects: dict[int, Access | None] = {}

    # happenings are ints: 2*step (start), 2*step+1 (end)

    def _ground(self) -> tuple[GroundAction, ...]:
        out: list[GroundAction] = []
        actions = {a.name: a for a in self.domain.actions}
        # plans repeat actions (a robot going back and forth): ground each once, all
        # in the same initial state, and share the (frozen) result
        seen: dict[tuple[str, tuple[str, ...]], GroundAction] = {}
        for i, step in enumerate(self.steps):
            key = (step.action, tuple(step.arguments))
            known = seen.get(key)
            if known is not None:
                out.append(known)
                continue
            action = actions.get(step.action)
            if action is None:
                raise ExecutionError(
                    f"plan step {i} {step.text}: domain {self.domain.name!r} "
                    f"has no action {step.action!r}"
                )
            if len(action.parameters) != len(step.arguments):
                raise ExecutionError(
                    f"plan step {i} {step.text}: action {step.action!r} takes "
                    f"{len(action.parameters)} arguments, got {len(step.arguments)}"
                )
            try:
                ground = seen[key] = self.ev.ground_action(action, step.arguments, self.initial)
                out.append(ground)
            except Exception as exc:  # the evaluator's own error names the cause
                raise ExecutionError(f"plan step {i} {step.text}: {exc}") from exc
        return tuple(out)

    def build(self, *, reduce: bool) -> PlanGraph:
        ground = self._ground()
        order = happening_order(self.steps)
        self.pos = {h: p for p, h in enumerate(order)}
        state = self.initial
        open_over_all: dict[int, Collection[VarHistory]] = {}
        watchers: dict[VarHistory, set[int]] = {}
        for h in order:
            i, is_end = divmod(h, 2)
            g = ground[i]
            dur = self.steps[i].duration
            point_cond = g.at_end if is_end else g.at_start
            when: When = "at end" if is_end else "at start"
            for var in self._ground_vars(point_cond, state):
                self._read(var, h, h)
            if not self.ev.holds(point_cond, state, GROUND, dur):
                self._unexplained(i, when, point_cond, g, state)
            if is_end:
                # the over-all interval closes before the end effects
                # (no empty set made and dropped per happening: a watched
                # variable keeps its entry in ``watchers`` once it has one)
                for var in open_over_all.pop(i, ()):
                    watchers[var].discard(i)
            effect = g.end_effect if is_end else g.start_effect
            access, written = self._effect(effect, h, state)
            if access.plain:  # same adds and deletes in every state: no need to walk
                # (with_changes deletes first, so every atom added is then true)
                state = state.with_changes(adds=access.adds, deletes=access.deleted)
                for atom in access.adds:
                    self.achievers[atom] = i
            else:
                state = self.ev.apply(effect, state, GROUND, dur)
                for atom in access.adds:
                    if atom in state:
                        self.achievers[atom] = i
            if not is_end:
                ovars = self._ground_vars(g.over_all, state)
                for var in ovars:
                    self._read(var, h, h + 1)
                if not self.ev.holds(g.over_all, state, GROUND, dur):
                    self._unexplained(i, "over all", g.over_all, g, state)
                else:
                    open_over_all[i] = ovars
                    for var in ovars:
                        watching = watchers.get(var)
                        if watching is None:
                            watchers[var] = {i}
                        else:
                            watching.add(i)
            # re-check the over-all conditions this happening may have broken
            for var in written:
                for j in tuple(watchers.get(var, ())):
                    if j == i:
                        continue
                    gj = ground[j]
                    if not self.ev.holds(gj.over_all, state, GROUND, self.steps[j].duration):
                        self._unexplained(
                            j,
                            "over all",
                            gj.over_all,
                            gj,
                            state,
                            detail=f"is broken by step {i} {self.steps[i].text} while it runs",
                        )
                        for v in open_over_all.pop(j, ()):
                            watchers[v].discard(j)
        return self._result(ground, order, state, reduce=reduce)

    # ------------------------------------------------------------ accesses

    def _ground_vars(self, cond: Condition, state: State) -> Collection[VarHistory]:
        """The histories of ``_condition_vars`` of a ground condition, kept (in the
        order it was found) when it is the same in every state."""
        key = id(cond)
        if key not in self._fixed_reads:
            fixed = reads_fixed(cond, self.ev._derived_rules)
            self._fixed_reads[key] = (
                tuple(map(self._history, self._condition_vars(cond, GROUND, state)))
                if fixed
                else None
            )
        found = self._fixed_reads[key]
        if found is not None:
            return found
        return [self._history(v) for v in self._condition_vars(cond, GROUND, state)]

    def _condition_vars(
        self, cond: Condition, bindings: Mapping[str, str], state: State
    ) -> set[_Var]:
        return condition_vars(self.ev, cond, bindings, state)

    def _effect(
        self, effect: Effect, h: int, state: State
    ) -> tuple[EffectAccess, tuple[VarHistory, ...]]:
        """Record the effect's accesses; returns them and the histories written."""
        key = id(effect)
        if key not in self._fixed_effects:
            fixed = writes_fixed(effect)
            self._fixed_effects[key] = (
                self._resolve(effect_access(self.ev, effect, state, fixed)) if fixed else None
            )
        found = self._fixed_effects[key]
        if found is None:
            found = self._resolve(effect_access(self.ev, effect, state))
        access, read, writes, written = found
        for hist in read:
            self._read(hist, h, h)
        for hist, kind in writes:
            self._write(hist, h, kind)
        return access, written

    def _resolve(self, access: EffectAccess) -> Access:
        """``access`` with its variables' histories (the written ones in the order
        of ``access.written``)."""
        history = self._history
        return (
            access,
            tuple(map(history, access.read)),
            tuple((history(var), kind) for var, kind in access.writes),
            tuple(map(history, access.written)),
        )

    def _history(self, var: _Var) -> VarHistory:
        hist = self.vars.get(var)
        if hist is None:
            if var[0] == "a":
                atom = var[1]
                assert isinstance(atom, Atom)
                hist = VarHistory(var, True, "add" if atom in self.initial else "del")
            else:
                hist = VarHistory(var, False, "read")
            self.vars[var] = hist
        return hist

    def _read(self, hist: VarHistory, head: int, tail: int) -> None:
        if hist.is_atom:
            # an atom's reads see the value of the current run; link from its latest writer
            if hist.latest_effect is not None:
                self._edge(hist.latest_effect, head, "causal", hist)
            hist.current.append((tail, None))
            return
        if hist.kind == "read":
            for src, _ in hist.previous:
                self._edge(src, head, "causal", hist)
            hist.current.append((tail, None))
            return
        hist.previous = hist.current
        hist.current = [(tail, None)]
        hist.kind = "read"
        for src, _ in hist.previous:
            self._edge(src, head, "causal", hist)

    def _write(self, hist: VarHistory, h: int, kind: str) -> None:
        if hist.kind == kind and kind != "assign":
            members = hist.previous
        else:
            hist.previous = hist.current
            hist.current = []
            hist.kind = kind
            members = hist.previous
        if members:  # _edge inlined: a write may follow many readers
            pos, edges, mine, step = self.pos, self.edges, self.pos[h], h // 2
            for src, role in members:
                if src // 2 == step or pos[src] >= mine:
                    continue
                if (src, h) not in edges:  # a causal or earlier reason stays
                    edges[(src, h)] = ("effects" if role == "effects" else "threat", hist)
        hist.current.append((h, "effects"))
        hist.latest_effect = h

    def _edge(self, src: int, dst: int, kind: Kind, hist: VarHistory) -> None:
        if src // 2 == dst // 2:
            return
        if self.pos[src] >= self.pos[dst]:
            # never order against the plan (an over-all read that ends after this
            # happening: either the plan is wrong, which check() reports, or the
            # atom was read by a branch of the condition that does not matter)
            return
        key = (src, dst)
        found = self.edges.get(key)
        if found is None or (kind == "causal" and found[0] != "causal"):
            self.edges[key] = (kind, hist)

    def _unexplained(
        self,
        i: int,
        when: When,
        cond: Condition,
        g: GroundAction,
        state: State,
        detail: str = "",
    ) -> None:
        text = describe_unmet(self.ev, cond, state, GROUND, self.steps[i].duration)
        self.unexplained.append(UnexplainedRequirement(i, self.steps[i].text, when, text, detail))

    # ------------------------------------------------------------ result

    def _result(
        self, ground: tuple[GroundAction, ...], order: list[int], state: State, *, reduce: bool
    ) -> PlanGraph:
        n = len(self.steps)
        succ: dict[int, list[int]] = {}
        for src, dst in self.edges:
            succ.setdefault(src, []).append(dst)
        kept = transitive_reduction(order, succ, self.pos) if reduce else set(self.edges)
        orderings, start_waits, end_waits, steps = orderings_of(
            kept, self.edges, self.pos, n, subject_text
        )
        step_order: list[int] = []
        seen: set[int] = set()
        for h in order:
            if h // 2 not in seen:
                seen.add(h // 2)
                step_order.append(h // 2)
        return PlanGraph(
            plan=self.plan,
            steps=self.steps,
            ground=ground,
            orderings=tuple(orderings),
            unexplained=tuple(self.unexplained),
            achievers=self.achievers,
            final_state=state,
            _start_waits=start_waits,
            _end_waits=end_waits,
            _order=step_order,
            _step_edges=steps,
        )
