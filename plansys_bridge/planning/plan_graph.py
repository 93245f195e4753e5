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

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TypeAlias

import networkx as nx

from plansys_bridge.errors import ExecutionError
from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import (
    And,
    Atom,
    Condition,
    Domain,
    Effect,
    NumericEffect,
    WhenEffect,
)
from plansys_bridge.planning.effect_access import (
    expr_fluents,
    ground_fluent,
    numeric_class,
    walk_effect,
)
from plansys_bridge.planning.happening_order import (
    happening_order,
    point_of,
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

_Var: TypeAlias = tuple[str, object]
"""("a", Atom) for a ground atom, ("f", FluentKey) for a numeric fluent."""


# ---------------------------------------------------------------- the result


@dataclass
class PlanGraph:
    """The plan's dependency graph.

    ``graph`` (networkx ``DiGraph``) has one node per plan step index (attributes
    ``action`` text, ``time``, ``duration``) and an edge ``i -> j`` when some
    happening of ``j`` must wait for some happening of ``i``; edge attributes:
    ``reason`` (readable text), ``orderings`` (list of :class:`Ordering`) and
    ``points`` (set of ``(source_point, target_point)`` pairs). Edges are
    transitively reduced at the level of happenings.
    """

    plan: Plan
    steps: tuple[PlanStep, ...]
    ground: tuple[GroundAction, ...]
    graph: nx.DiGraph
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
    return _Builder(plan, domain, state, ev).build(reduce=reduce)


@dataclass
class _VarHistory:
    """Accesses of one variable, grouped in runs of mutually commuting accesses."""

    kind: str | None  # kind of the current run
    current: list[tuple[int, Kind | None]] = field(default_factory=list)
    """(tail happening, access role) of the current run's members."""
    previous: list[tuple[int, Kind | None]] = field(default_factory=list)
    latest_effect: int | None = None


class _Builder:
    def __init__(self, plan: Plan, domain: Domain, state: State, ev: Evaluator) -> None:
        self.plan = plan
        self.domain = domain
        self.initial = state
        self.ev = ev
        self.steps = tuple(plan.steps)
        self.edges: dict[tuple[int, int], tuple[Kind, str]] = {}
        self.vars: dict[_Var, _VarHistory] = {}
        self.unexplained: list[UnexplainedRequirement] = []
        self.achievers: dict[Atom, int] = {}

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
        open_over_all: dict[int, set[_Var]] = {}
        watchers: dict[_Var, set[int]] = {}
        for h in order:
            i, is_end = divmod(h, 2)
            g = ground[i]
            dur = self.steps[i].duration
            point_cond = g.at_end if is_end else g.at_start
            when: When = "at end" if is_end else "at start"
            for var in self._condition_vars(point_cond, GROUND, state):
                self._read(var, h, h)
            if not self.ev.holds(point_cond, state, GROUND, dur):
                self._unexplained(i, when, point_cond, g, state)
            if is_end:
                # the over-all interval closes before the end effects
                for var in open_over_all.pop(i, set()):
                    watchers.get(var, set()).discard(i)
            effect = g.end_effect if is_end else g.start_effect
            touched = self._effect(effect, g, h, state)
            state = self.ev.apply(effect, state, GROUND, dur)
            added, written = touched
            for atom in added:
                if atom in state:
                    self.achievers[atom] = i
            if not is_end:
                ovars = self._condition_vars(g.over_all, GROUND, state)
                for var in ovars:
                    self._read(var, h, h + 1)
                if not self.ev.holds(g.over_all, state, GROUND, dur):
                    self._unexplained(i, "over all", g.over_all, g, state)
                else:
                    open_over_all[i] = ovars
                    for var in ovars:
                        watchers.setdefault(var, set()).add(i)
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
                        for v in open_over_all.pop(j, set()):
                            watchers.get(v, set()).discard(j)
        return self._result(ground, order, state, reduce=reduce)

    # ------------------------------------------------------------ accesses

    def _condition_vars(
        self, cond: Condition, bindings: Mapping[str, str], state: State
    ) -> set[_Var]:
        """Every base atom and fluent ``cond`` reads in ``state`` (derived predicates
        expanded; of a disjunction only the branch that holds there)."""
        if isinstance(cond, And) and not cond.operands:
            return set()
        pos, neg = self.ev.condition_atoms(cond, bindings, state)
        out: set[_Var] = {("a", atom) for atom in pos | neg}
        out |= {("f", key) for key in self.ev.condition_fluents(cond, bindings, state)}
        return out

    def _effect(
        self, effect: Effect, g: GroundAction, h: int, state: State
    ) -> tuple[set[Atom], set[_Var]]:
        """Record the effect's accesses; returns (atoms added, variables written)."""
        adds, deletes, numeric = self.ev.effect_atoms(effect, GROUND, state)
        written: set[_Var] = set()
        read: set[_Var] = set()
        # conditions of conditional effects and values of numeric effects are reads
        ops: dict[FluentKey, str] = {}
        for sub, binds in walk_effect(effect, GROUND, self.ev, state):
            if isinstance(sub, WhenEffect):
                read |= self._condition_vars(sub.condition, binds, state)
            elif isinstance(sub, NumericEffect):
                key = ground_fluent(sub.fluent, binds)
                if key is not None:
                    cls = numeric_class(sub.op)
                    ops[key] = cls if ops.get(key, cls) == cls else "assign"
                read |= {("f", k) for k in expr_fluents(sub.value, binds)}
        for var in read:
            self._read(var, h, h)
        for atom in deletes - adds:
            self._write(("a", atom), h, "del")
            written.add(("a", atom))
        for atom in adds:
            self._write(("a", atom), h, "add")
            written.add(("a", atom))
        for key in numeric:
            self._write(("f", key), h, ops.get(key, "assign"))
            written.add(("f", key))
        return adds, written

    def _history(self, var: _Var) -> _VarHistory:
        hist = self.vars.get(var)
        if hist is None:
            if var[0] == "a":
                atom = var[1]
                assert isinstance(atom, Atom)
                hist = _VarHistory(kind="add" if atom in self.initial else "del")
            else:
                hist = _VarHistory(kind="read")
            self.vars[var] = hist
        return hist

    def _read(self, var: _Var, head: int, tail: int) -> None:
        hist = self._history(var)
        if var[0] == "a":
            # an atom's reads see the value of the current run; link from its latest writer
            if hist.latest_effect is not None:
                self._edge(hist.latest_effect, head, "causal", var)
            hist.current.append((tail, None))
            return
        if hist.kind == "read":
            for src, _ in hist.previous:
                self._edge(src, head, "causal", var)
            hist.current.append((tail, None))
            return
        hist.previous = hist.current
        hist.current = [(tail, None)]
        hist.kind = "read"
        for src, _ in hist.previous:
            self._edge(src, head, "causal", var)

    def _write(self, var: _Var, h: int, kind: str) -> None:
        hist = self._history(var)
        if hist.kind == kind and kind != "assign":
            members = hist.previous
        else:
            hist.previous = hist.current
            hist.current = []
            hist.kind = kind
            members = hist.previous
        for src, role in members:
            self._edge(src, h, "effects" if role == "effects" else "threat", var)
        hist.current.append((h, "effects"))
        hist.latest_effect = h

    def _edge(self, src: int, dst: int, kind: Kind, var: _Var) -> None:
        if src // 2 == dst // 2:
            return
        if self.pos[src] >= self.pos[dst]:
            # never order against the plan (an over-all read that ends after this
            # happening: either the plan is wrong, which check() reports, or the
            # atom was read by a branch of the condition that does not matter)
            return
        key = (src, dst)
        if key not in self.edges or (kind == "causal" and self.edges[key][0] != "causal"):
            self.edges[key] = (kind, _var_text(var))

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
        orderings: list[Ordering] = []
        start_waits: list[list[tuple[int, Point]]] = [[] for _ in range(n)]
        end_waits: list[list[tuple[int, Point]]] = [[] for _ in range(n)]
        graph = nx.DiGraph()
        for i, step in enumerate(self.steps):
            graph.add_node(i, action=step.text, time=step.time, duration=step.duration)
        for src, dst in sorted(kept, key=lambda e: (self.pos[e[1]], self.pos[e[0]])):
            kind, subject = self.edges[(src, dst)]
            o = Ordering(src // 2, point_of(src), dst // 2, point_of(dst), kind, subject)
            orderings.append(o)
            (end_waits if dst % 2 else start_waits)[dst // 2].append((o.source, o.source_point))
            if graph.has_edge(o.source, o.target):
                data = graph.edges[o.source, o.target]
                data["orderings"].append(o)
                data["points"].add((o.source_point, o.target_point))
                data["reason"] += "; " + o.reason
            else:
                graph.add_edge(
                    o.source,
                    o.target,
                    reason=o.reason,
                    orderings=[o],
                    points={(o.source_point, o.target_point)},
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
            graph=graph,
            orderings=tuple(orderings),
            unexplained=tuple(self.unexplained),
            achievers=self.achievers,
            final_state=state,
            _start_waits=[tuple(w) for w in start_waits],
            _end_waits=[tuple(w) for w in end_waits],
            _order=step_order,
        )


def _var_text(var: _Var) -> str:
    if var[0] == "a":
        return str(var[1])
    key: FluentKey = var[1]  # type: ignore[assignment]
    return "(" + " ".join((key[0], *key[1])) + ")"
