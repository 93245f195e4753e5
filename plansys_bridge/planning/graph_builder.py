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
then records all its accesses in one call whose loops do the common atom cases
inline. Atoms keep their truth values in their histories: a condition of literals
is checked, and a plain effect applied, on those, and a State is made only when the
evaluator needs one. What depends on the state takes the general way each time.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from plansys_bridge.errors import ExecutionError
from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import And, Atom, Condition, Domain, Effect
from plansys_bridge.planning.effect_access import (
    Var,
    condition_vars,
    effect_access,
    fixed_condition_vars,
    fixed_effect_access,
    literal_atoms,
    reads_fixed,
    writes_fixed,
    written_names,
)
from plansys_bridge.planning.orderings import GROUND, Kind, UnexplainedRequirement, When
from plansys_bridge.planning.plan import PlanStep
from plansys_bridge.planning.requirement_text import describe_unmet
from plansys_bridge.planning.var_history import Access, VarHistory

__all__ = ["Edges", "GraphBuilder"]

Edges = dict[tuple[int, int], tuple[Kind, VarHistory]]
"""(source happening, target happening) -> why, and on which variable."""

_Reads = tuple[VarHistory, ...] | None
"""A condition's histories, in the order it reads them; None: ask at each happening."""

_Lits = tuple[tuple[VarHistory, ...], tuple[VarHistory, ...]] | None
"""The histories of the atoms a condition of literals needs true and false; None:
the condition is not only literals (the evaluator decides whether it holds)."""


class _Moves:
    """What one ground action's happenings read and write, worked out the first
    time each part is needed (a part that depends on the state stays ``None``)."""

    __slots__ = (
        "check_end",
        "check_over",
        "check_start",
        "end",
        "end_access",
        "end_lits",
        "over",
        "over_holds",
        "over_lits",
        "start",
        "start_access",
        "start_lits",
        "watched",
    )

    def __init__(self, g: GroundAction) -> None:
        # an empty conjunction holds everywhere and reads nothing: not asked at all
        self.check_start = type(g.at_start) is not And or bool(g.at_start.operands)
        self.check_over = type(g.over_all) is not And or bool(g.over_all.operands)
        self.check_end = type(g.at_end) is not And or bool(g.at_end.operands)
        self.start: _Reads = None
        self.start_lits: _Lits = None
        self.start_access: Access | None = None
        self.over: _Reads = None
        self.over_lits: _Lits = None
        self.watched: tuple[VarHistory, ...] = ()
        self.over_holds: bool | None = None
        """Whether the over-all requirement holds, kept when its value cannot change
        during the plan (literals of atoms no action of the plan changes)."""
        self.end: _Reads = None
        self.end_lits: _Lits = None
        self.end_access: Access | None = None


def _all_hold(lits: tuple[tuple[VarHistory, ...], tuple[VarHistory, ...]]) -> bool:
    """Whether a condition of literals holds where the simulation is: its positive
    atoms true and its negated ones false (the at-start check does this inline)."""
    for hist in lits[0]:
        if not hist.value:
            return False
    for hist in lits[1]:  # noqa: SIM110 (any() of a generator: a call per atom)
        if hist.value:
            return False
    return True


_AT_START: When = "at start"
_AT_END: When = "at end"
_PARTS = ("start", "end")
_ACCESS_PARTS = ("start_access", "end_access")
"""The :class:`_Moves` slots of a happening's condition reads and effect access,
by the happening's parity."""


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
        self._atoms: dict[tuple[str, tuple[str, ...]], VarHistory] = {}
        self._fluents: dict[FluentKey, VarHistory] = {}
        """The histories, by atom (predicate, arguments) and by fluent."""
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
        self._moves: Sequence[_Moves] = ()
        self._changeable: set[tuple[str, str]] | None = set()
        self._derived = ev._derived_rules

    # ------------------------------------------------------------ grounding

    def ground(self) -> tuple[tuple[GroundAction, ...], list[_Moves]]:
        """Every step's ground action and its (shared) moves; an unknown action or a
        wrong argument list raises :class:`ExecutionError` naming the step."""
        actions = {a.name: a for a in self.domain.actions}
        # plans repeat actions (a robot going back and forth): ground each once, all
        # in the same initial state, and share the (frozen) result
        seen: dict[tuple[str, tuple[str, ...]], tuple[GroundAction, _Moves]] = {}
        changeable = self._changeable
        named: set[str] = set()  # grounding only substitutes arguments: names stay
        keys = [
            (s.action, s.arguments if type(s.arguments) is tuple else tuple(s.arguments))
            for s in self.steps
        ]
        for i, key in enumerate(keys):
            if key in seen:
                continue
            step = self.steps[i]
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
                g = self.ev.ground_action(action, step.arguments, self.initial)
            except Exception as exc:  # the evaluator's own error names the cause
                raise ExecutionError(f"plan step {i} {step.text}: {exc}") from exc
            seen[key] = (g, _Moves(g))
            if changeable is not None and step.action not in named:
                named.add(step.action)
                for effect in (g.start_effect, g.end_effect):
                    names = written_names(effect) if changeable is not None else None
                    changeable = None if names is None else changeable | names  # type: ignore[operator]
        self._changeable = changeable
        found = [seen[key] for key in keys]
        return tuple([g for g, _ in found]), [m for _, m in found]

    # ------------------------------------------------------------ simulating

    def simulate(
        self, ground: Sequence[GroundAction], moves: Sequence[_Moves], order: Sequence[int]
    ) -> State:
        """Run the happenings in ``order``; returns the state the plan leads to."""
        pos = self.pos = [0] * (2 * len(self.steps))
        for p, h in enumerate(order):
            pos[h] = p
        self._order, self._moves = order, moves
        ev, steps, achieved = self.ev, self.steps, self.achieved
        holds = ev.holds
        open_over_all: dict[int, Collection[VarHistory]] = {}
        watchers: dict[VarHistory, set[int]] = {}
        for p, h in enumerate(order):
            i = h >> 1
            g = ground[i]
            m = moves[i]
            end = h & 1
            if end:
                cond, effect, check = g.at_end, g.end_effect, m.check_end
                reads, lits, access, when = m.end, m.end_lits, m.end_access, _AT_END
            else:
                cond, effect, check = g.at_start, g.start_effect, m.check_start
                reads, lits, access, when = m.start, m.start_lits, m.start_access, _AT_START
            if check:
                if reads is None:
                    reads, lits = self._reads(cond, m, _PARTS[end])
                if lits is None:
                    ok = holds(cond, self._state(), GROUND, steps[i].duration)
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
                access = self._access(effect, m, _ACCESS_PARTS[end])
            found, read, writes, written, added, dropped = access
            if found.plain:  # same adds and deletes in every state: truth values only
                for hist in dropped:
                    hist.value = False
                for hist in added:
                    hist.value = True
                    achieved[hist] = i
            else:
                state = self.state = ev.apply(effect, self._state(), GROUND, steps[i].duration)
                self.synced = p + 1
                for hist in written:
                    if hist.is_atom:
                        hist.value = hist.var[1] in state
                for hist in added:
                    if hist.value:
                        achieved[hist] = i
            self.applied = p + 1
            over: Collection[VarHistory] = ()
            if not end and m.check_over:
                over_lits = m.over_lits
                if m.over is None:
                    over, over_lits = self._reads(g.over_all, m, "over")
                else:
                    over = m.over
            self._record(h, reads + read if reads and read else reads or read, writes, over)
            if not end and m.check_over:
                ok = m.over_holds  # type: ignore[assignment]
                if ok is None:
                    if over_lits is None:
                        ok = holds(g.over_all, self._state(), GROUND, steps[i].duration)
                    else:
                        ok = _all_hold(over_lits)
                    if m.over is not None and not m.watched and over_lits is not None:
                        m.over_holds = ok  # reads only what no action changes
                if not ok:
                    self._unexplained(i, "over all", g.over_all)
                else:
                    watched = m.watched if m.over is not None else self._watched(over)
                    if watched:
                        open_over_all[i] = watched
                        for var in watched:
                            if var in watchers:
                                watchers[var].add(i)
                            else:
                                watchers[var] = {i}
            # re-check the over-all conditions this happening may have broken
            if watchers:
                for var in written:
                    if watchers.get(var):
                        self._recheck(i, watchers[var], ground, open_over_all, watchers)
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
        open_over_all: dict[int, Collection[VarHistory]],
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

    def _reads(self, cond: Condition, m: _Moves, part: str) -> tuple[tuple[VarHistory, ...], _Lits]:
        """The histories ``cond`` reads where the simulation is, and its literals'
        histories (None: not only literals), kept in ``m`` (with the over-all ones
        worth watching) when they are the same in every state."""
        fixed = reads_fixed(cond, self._derived)
        listed = fixed_condition_vars(cond) if fixed else None
        if listed is None:
            listed = condition_vars(self.ev, cond, GROUND, self._state())
        history = self._history
        found = tuple(map(history, listed))
        lits: _Lits = None
        if fixed:
            setattr(m, part, found)
            atoms = literal_atoms(cond)
            if atoms is not None:  # every atom read has its history by now
                kept = self._atoms
                lits = (
                    tuple([kept[a.predicate, a.args] for a in atoms[0]]),
                    tuple([kept[a.predicate, a.args] for a in atoms[1]]),
                )
                setattr(m, part + "_lits", lits)
            if part == "over":
                m.watched = self._watched(found)
        return found, lits

    def _watched(self, over: Collection[VarHistory]) -> tuple[VarHistory, ...]:
        """The over-all reads some action may change (only they can be broken)."""
        return tuple(var for var in over if var.changeable)

    def _access(self, effect: Effect, m: _Moves, part: str) -> Access:
        """What ``effect`` reads and writes where the simulation is, kept in ``m``
        when it is the same in every state."""
        fixed = writes_fixed(effect)
        access = fixed_effect_access(effect) if fixed else None
        if access is None:
            access = effect_access(self.ev, effect, self._state(), fixed)
        history = self._history
        # each variable written is looked up once (the written, added and deleted
        # ones are all among the writes)
        of = {var: history(var) for var, _ in access.writes}
        found = (
            access,
            tuple(map(history, access.read)),
            tuple([(of[var], kind) for var, kind in access.writes]),
            tuple([of[var] for var in access.written]),
            tuple([of["a", atom] for atom in access.adds]),
            tuple([of["a", atom] for atom in access.deleted]),
        )
        if fixed:
            setattr(m, part, found)
        return found

    def _history(self, var: Var) -> VarHistory:
        """``var``'s history, made on first use. Kept by the atom's predicate and
        arguments (or the fluent's key): hashing and comparing those takes no
        Python call, while an :class:`Atom`'s equality is one."""
        if var[0] == "a":
            atom: Atom = var[1]  # type: ignore[assignment]
            try:
                return self._atoms[atom.predicate, atom.args]
            except KeyError:
                value = atom in self.initial
                hist = VarHistory(var, True, "add" if value else "del", value=value)
                self._atoms[atom.predicate, atom.args] = hist
                name = atom.predicate
        else:
            key: FluentKey = var[1]  # type: ignore[assignment]
            try:
                return self._fluents[key]
            except KeyError:
                hist = self._fluents[key] = VarHistory(var, False, "read")
                name = key[0]
        changeable = self._changeable
        hist.changeable = changeable is None or (var[0], name) in changeable
        return hist

    def _record(
        self,
        h: int,
        reads: Sequence[VarHistory],
        writes: Sequence[tuple[VarHistory, str]],
        over: Collection[VarHistory],
    ) -> None:
        """Happening ``h``'s accesses, in one call: it reads ``reads``, then writes
        ``writes``, then (a start) reads its over-all requirement's ``over`` until
        its step's end.

        An atom read waits for the atom's latest writer (written out here: a
        happening makes a few such reads); a fluent read takes :meth:`_read`. A
        write goes after the members of the variable's previous run (a write of the
        current run's kind commutes with the run, except an assignment), keeping a
        causal or earlier reason for a pair."""
        pos, edges, succ, mine, step = self.pos, self.edges, self.succ, self.pos[h], h >> 1
        tail = h
        for group in (reads, over):
            for hist in group:
                if not hist.is_atom:
                    self._read(hist, h, tail)
                    continue
                src = hist.latest_effect
                if src is not None and src >> 1 != step and pos[src] < mine:
                    if (src, h) not in edges:
                        edges[(src, h)] = ("causal", hist)
                        succ[src].append(h)
                    elif edges[(src, h)][0] != "causal":
                        edges[(src, h)] = ("causal", hist)
                hist.current.append((tail, None))
            if tail != h:
                break
            tail = h + 1  # the writes come between the reads and the over-all reads
            for hist, kind in writes:
                if hist.kind == kind and kind != "assign":
                    members = hist.previous
                else:
                    members = hist.previous = hist.current
                    hist.current = []
                    hist.kind = kind
                for src, role in members:
                    if src >> 1 == step or pos[src] >= mine or (src, h) in edges:
                        continue
                    edges[(src, h)] = ("effects" if role == "effects" else "threat", hist)
                    succ[src].append(h)
                hist.current.append((h, "effects"))
                hist.latest_effect = h

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
