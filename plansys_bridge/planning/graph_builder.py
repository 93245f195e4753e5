"""Simulating a plan's happenings to find which must wait for which.

The plan's happenings are simulated in plan order on the current knowledge (see
:mod:`plansys_bridge.planning.plan_graph` for what the orderings mean). Each ground
atom and numeric fluent has a :class:`~plansys_bridge.planning.var_history.VarHistory`
of accesses; accesses that do not commute are ordered as in the plan, and every
condition is evaluated exactly so that an unexplained requirement can be named.

Why it is shaped as it is: the executor builds this graph once per plan, and a plan
repeats few ground actions many times (a robot going round and round). So what a
ground action's start, over-all and end read and write is worked out once per
ground action (when it is the same in every state, see
:func:`~plansys_bridge.planning.effect_access.reads_fixed`), and each happening
then records its accesses in the simulation loop itself (the common atom cases
written out). Atoms keep their truth values in their histories: a condition of literals
is checked, and a plain effect applied, on those, and a State is made only when the
evaluator needs one. What depends on the state takes the general way each time.
"""

from __future__ import annotations

from collections.abc import Sequence

from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Condition, Domain
from plansys_bridge.planning.ground_moves import Histories, Moves, all_hold, recorded, watched
from plansys_bridge.planning.orderings import GROUND, Kind, UnexplainedRequirement, When
from plansys_bridge.planning.plan import PlanStep
from plansys_bridge.planning.requirement_text import describe_unmet
from plansys_bridge.planning.var_history import VarHistory

__all__ = ["Edges", "GraphBuilder"]

Edges = dict[tuple[int, int], tuple[Kind, VarHistory]]
"""(source happening, target happening) -> why, and on which variable."""

_AT_START: When = "at start"
_AT_END: When = "at end"
_PARTS = ("start", "end")
_ACCESS_PARTS = ("start_access", "end_access")
_REC_PARTS = ("start_rec", "end_rec")
"""The :class:`Moves` slots of a happening's condition reads, effect access and
recorded reads, by the happening's parity."""


class GraphBuilder:
    """One build: ground the steps, simulate their happenings, keep the edges.

    Happenings are ints: ``2*step`` (start), ``2*step+1`` (end).
    """

    def __init__(self, steps: Sequence[PlanStep], domain: Domain, state: State, ev: Evaluator):
        self.domain = domain
        self.initial = state
        self.ev = ev
        self.steps = tuple(steps)
        self.edges: Edges = {}
        self.succ: list[list[int]] = [[] for _ in range(2 * len(self.steps))]
        """Per happening, the targets of its edges (in the order they were found)."""
        self.histories = Histories(state, ev)
        self.unexplained: list[UnexplainedRequirement] = []
        self.achieved: dict[VarHistory, int] = {}
        """Per atom's history, the step whose effect last set it (keyed by history:
        hashing an atom is a Python call, a history's identity hash is not)."""
        self.pos: list[int] = []
        self.state = state
        """The simulated state once the first ``synced`` happenings of the order
        are applied; ``applied`` happenings are (on the atoms' truth values)."""
        self.synced = 0
        self.applied = 0
        self._order: Sequence[int] = ()
        self._moves: Sequence[Moves] = ()

    def ground(self) -> tuple[tuple[GroundAction, ...], list[Moves]]:
        """Every step's ground action and its (shared) moves; an unknown action or a
        wrong argument list raises :class:`ExecutionError` naming the step."""
        return self.histories.ground(self.steps, self.domain)

    # ------------------------------------------------------------ simulating

    def simulate(
        self, ground: Sequence[GroundAction], moves: Sequence[Moves], order: Sequence[int]
    ) -> None:
        """Run the happenings in ``order``; :meth:`final_state` is then the state the
        plan leads to (made when asked: the executor never asks)."""
        pos = self.pos = [0] * (2 * len(self.steps))
        for p, h in enumerate(order):
            pos[h] = p
        self._order, self._moves = order, moves
        ev, steps, achieved, hs, now = (
            self.ev,
            self.steps,
            self.achieved,
            self.histories,
            self._state,
        )
        holds, edges, succ = ev.holds, self.edges, self.succ
        open_over_all: dict[int, tuple[VarHistory, ...]] = {}
        watchers: dict[VarHistory, set[int]] = {}
        for p, h in enumerate(order):
            i = h >> 1
            g = ground[i]
            m = moves[i]
            end = h & 1
            if end:
                cond, effect, check = g.at_end, g.end_effect, m.check_end
                reads, lits, access, rec, when = m.end, m.end_lits, m.end_access, m.end_rec, _AT_END
            else:
                cond, effect, check = g.at_start, g.start_effect, m.check_start
                reads, lits, access, rec = m.start, m.start_lits, m.start_access, m.start_rec
                when = _AT_START
            if check:
                if reads is None:
                    reads, lits = hs.reads(cond, m, _PARTS[end], now)
                if lits is None:
                    ok = holds(cond, now(), GROUND, steps[i].duration)
                else:  # literals: read off the atoms' truth values (no state, no call)
                    ok = True
                    for hist in lits[0]:
                        if not hist.value:
                            ok = False
                            break
                    else:
                        for hist in lits[1]:
                            if hist.value:
                                ok = False
                                break
                if not ok:
                    self._unexplained(i, when, cond)
            # the over-all interval closes before the end effects
            # (a watched variable keeps its entry in ``watchers`` once it has one)
            if end and i in open_over_all:
                for var in open_over_all.pop(i):
                    watchers[var].discard(i)
            if access is None:
                access = hs.access(effect, m, _ACCESS_PARTS[end], now)
            found, read, writes, written, added, dropped = access
            if found.plain:  # same adds and deletes in every state: truth values only
                for hist in dropped:
                    hist.value = False
                for hist in added:
                    hist.value = True
                    achieved[hist] = i
            else:
                state = self.state = ev.apply(effect, now(), GROUND, steps[i].duration)
                self.synced = p + 1
                for hist in written:
                    if hist.is_atom:
                        hist.value = hist.var[1] in state
                for hist in added:
                    if hist.value:
                        achieved[hist] = i
            self.applied = p + 1
            if rec is None:
                rec = recorded(reads or (), read)
                if (
                    getattr(m, _PARTS[end]) is not None
                    and getattr(m, _ACCESS_PARTS[end]) is not None
                ):
                    setattr(m, _REC_PARTS[end], rec)
            over_check = not end and m.check_over
            keep: tuple[VarHistory, ...] = ()
            if over_check:  # read after the start effects, until the step's end
                over_lits = m.over_lits
                if m.over is None:
                    over, over_lits = hs.reads(g.over_all, m, "over", now)
                    keep = m.watched if m.over is not None else watched(over)
                else:
                    keep = m.watched
            # the happening's accesses: its reads, its writes, its over-all reads.
            # An atom read waits for the atom's latest writer; a write goes after
            # the members of the variable's previous run (a write of the current
            # run's kind commutes with the run, except an assignment), keeping a
            # causal or earlier reason for a pair. Written out here: this is
            # done for every happening, mostly on a few atoms.
            mine = pos[h]
            mark: tuple[int, Kind | None] = (h, None)
            for hist in rec:
                if hist.is_atom:
                    src = hist.latest_effect
                    if src is not None and src >> 1 != i and pos[src] < mine:
                        link = edges.get((src, h))
                        if link is None:
                            edges[(src, h)] = ("causal", hist)
                            succ[src].append(h)
                        elif link[0] != "causal":
                            edges[(src, h)] = ("causal", hist)
                    hist.current.append(mark)
                else:
                    self._read(hist, h, h)
            if writes:
                mark = (h, "effects")
                for hist, kind in writes:
                    if hist.kind == kind and kind != "assign":
                        members = hist.previous
                    else:
                        members = hist.previous = hist.current
                        hist.current = []
                        hist.kind = kind
                    for src, role in members:
                        if src >> 1 == i or pos[src] >= mine or (src, h) in edges:
                            continue
                        edges[(src, h)] = ("effects" if role == "effects" else "threat", hist)
                        succ[src].append(h)
                    hist.current.append(mark)
                    hist.latest_effect = h
            if over_check:
                for hist in keep:
                    self._read_over(hist, h)
                ok = m.over_holds  # type: ignore[assignment]
                if ok is None:
                    if over_lits is None:
                        ok = holds(g.over_all, now(), GROUND, steps[i].duration)
                    else:
                        ok = all_hold(over_lits)
                    if m.over is not None and not m.watched and over_lits is not None:
                        m.over_holds = ok  # reads only what no action changes
                if not ok:
                    self._unexplained(i, "over all", g.over_all)
                elif keep:  # watched until the end: only what some action changes
                    open_over_all[i] = keep
                    for var in keep:
                        if var in watchers:
                            watchers[var].add(i)
                        else:
                            watchers[var] = {i}
            # re-check the over-all conditions this happening may have broken
            if watchers:
                for var in written:
                    if watchers.get(var):
                        self._recheck(i, watchers[var], ground, open_over_all, watchers)

    def final_state(self) -> State:
        """The state the plan leads to (once :meth:`simulate` has run)."""
        return self._state()

    def _state(self) -> State:
        """The simulated state, brought up to date with the plain effects applied
        since it was last made (on the atoms' truth values only).

        Why: most happenings need no state (their conditions are literals, their
        effects plain), so the state is made only when the evaluator needs one,
        in one change for all the happenings since the last time."""
        if self.synced < self.applied:
            moves = self._moves
            changed: dict[VarHistory, None] = {}
            for h in self._order[self.synced : self.applied]:
                m = moves[h >> 1]
                access = m.end_access if h & 1 else m.start_access
                assert access is not None  # a plain effect's access is kept
                for hist in access[5]:
                    changed[hist] = None
                for hist in access[4]:
                    changed[hist] = None
            self.state = self.state.with_facts(
                [hist.var[1] for hist in changed if not hist.value],  # type: ignore[misc]
                [hist.var[1] for hist in changed if hist.value],  # type: ignore[misc]
            )
            self.synced = self.applied
        return self.state

    def _recheck(
        self,
        i: int,
        watching: set[int],
        ground: Sequence[GroundAction],
        open_over_all: dict[int, tuple[VarHistory, ...]],
        watchers: dict[VarHistory, set[int]],
    ) -> None:
        """Check again the over-all requirements of the ``watching`` steps after step
        ``i`` changed a variable they read; a broken one is named and unwatched."""
        state = self._state()
        for j in tuple(watching):
            if j == i:
                continue
            gj = ground[j]
            if not self.ev.holds(gj.over_all, state, GROUND, self.steps[j].duration):
                detail = f"is broken by step {i} {self.steps[i].text} while it runs"
                self._unexplained(j, "over all", gj.over_all, detail)
                for v in open_over_all.pop(j, ()):
                    watchers[v].discard(j)

    # ------------------------------------------------------------ accesses

    def _read_over(self, hist: VarHistory, h: int) -> None:
        """Start ``h``'s read of ``hist`` for its over-all requirement (until the
        step's end ``h + 1``): an atom waits for its latest writer, a fluent for the
        last run of changes (:meth:`_read`)."""
        if not hist.is_atom:
            self._read(hist, h, h + 1)
            return
        src = hist.latest_effect
        if src is not None and src >> 1 != h >> 1 and self.pos[src] < self.pos[h]:
            self._edge(src, h, "causal", hist)
        hist.current.append((h + 1, None))

    def _read(self, hist: VarHistory, head: int, tail: int) -> None:
        """A fluent read: after every member of the last run of changes."""
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
        if found is None:
            self.edges[key] = (kind, hist)
            self.succ[src].append(dst)
        elif kind == "causal" and found[0] != "causal":
            self.edges[key] = (kind, hist)

    def _unexplained(self, i: int, when: When, cond: Condition, detail: str = "") -> None:
        text = describe_unmet(self.ev, cond, self._state(), GROUND, self.steps[i].duration)
        self.unexplained.append(UnexplainedRequirement(i, self.steps[i].text, when, text, detail))
