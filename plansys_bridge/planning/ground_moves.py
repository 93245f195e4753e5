"""Grounding a plan's steps, and what each ground action's happenings read and write.

The plan graph builder (:mod:`plansys_bridge.planning.graph_builder`) simulates a
plan's happenings and orders their accesses. What a ground action's start, over-all
and end read and write is worked out here, once per ground action when it is the
same in every state (see :func:`~plansys_bridge.planning.effect_access.reads_fixed`),
and resolved to the variables' :class:`~plansys_bridge.planning.var_history.VarHistory`
objects, so that each happening afterwards only walks tuples of histories.

Why apart from the simulation: a plan repeats few ground actions many times (a
robot going round and round), so this part runs a few times per ground action and
the simulation once per happening; each reads more easily on its own.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence

from plansys_bridge.errors import ExecutionError
from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import And, Atom, Condition, Domain, Effect
from plansys_bridge.planning.effect_access import (
    Var,
    condition_vars,
    effect_access,
    fixed_effect_access,
    fixed_reads,
    reads_fixed,
    var_key,
    writes_fixed,
    written_names,
)
from plansys_bridge.planning.orderings import GROUND
from plansys_bridge.planning.plan import PlanStep
from plansys_bridge.planning.var_history import Access, VarHistory

__all__ = ["Histories", "Lits", "Moves", "all_hold", "recorded"]

Reads = tuple[VarHistory, ...] | None
"""A condition's histories, in the order it reads them; None: ask at each happening."""

Lits = tuple[tuple[VarHistory, ...], tuple[VarHistory, ...]] | None
"""The histories of the atoms a condition of literals needs true and false; None:
the condition is not only literals (the evaluator decides whether it holds)."""


class Moves:
    """What one ground action's happenings read and write, worked out the first
    time each part is needed (a part that depends on the state stays ``None``)."""

    __slots__ = (
        "check_end",
        "check_over",
        "check_start",
        "end",
        "end_access",
        "end_lits",
        "end_rec",
        "over",
        "over_holds",
        "over_lits",
        "schema",
        "start",
        "start_access",
        "start_lits",
        "start_rec",
        "watched",
    )

    def __init__(self, g: GroundAction) -> None:
        self.schema = id(g.action) if g.action is not None else id(g)
        """The action the ground action was made of (by identity; its own when unknown)."""
        # an empty conjunction holds everywhere and reads nothing: not asked at all
        self.check_start = type(g.at_start) is not And or bool(g.at_start.operands)
        self.check_over = type(g.over_all) is not And or bool(g.over_all.operands)
        self.check_end = type(g.at_end) is not And or bool(g.at_end.operands)
        self.start: Reads = None if self.check_start else ()
        self.start_lits: Lits = None
        self.start_access: Access | None = None
        self.start_rec: tuple[VarHistory, ...] | None = None
        """The start's reads an effect may change (its condition's, then its
        effect's): the only ones that can order it after another happening."""
        self.over: Reads = None
        self.over_lits: Lits = None
        self.watched: tuple[VarHistory, ...] = ()
        self.over_holds: bool | None = None
        """Whether the over-all requirement holds, kept when its value cannot change
        during the plan (literals of atoms no action of the plan changes)."""
        self.end: Reads = None if self.check_end else ()
        self.end_lits: Lits = None
        self.end_access: Access | None = None
        self.end_rec: tuple[VarHistory, ...] | None = None


def all_hold(lits: tuple[tuple[VarHistory, ...], tuple[VarHistory, ...]]) -> bool:
    """Whether a condition of literals holds where the simulation is: its positive
    atoms true and its negated ones false (the at-start check does this inline)."""
    for hist in lits[0]:
        if not hist.value:
            return False
    for hist in lits[1]:  # noqa: SIM110 (any() of a generator: a call per atom)
        if hist.value:
            return False
    return True


def recorded(
    reads: Sequence[VarHistory], effect_reads: Sequence[VarHistory]
) -> tuple[VarHistory, ...]:
    """A happening's reads that can order it: those of variables some action of the
    plan may change. Why: a variable nothing writes has no writer to wait for and
    no later write to be waited on by, so recording its reads (an over-all
    ``connected`` read at every move) only made lists nobody walks."""
    return tuple([hist for hist in (*reads, *effect_reads) if hist.changeable])


class Histories:
    """The variables' histories of one build and the grounding of its steps.

    ``changeable`` is the set of ``("a", predicate)`` and ``("f", fluent)`` names
    some ground action of the plan may write (None: any), complete once
    :meth:`ground` has run; a history made after that knows whether it can change.
    """

    def __init__(self, initial: State, ev: Evaluator) -> None:
        self.initial = initial
        self.ev = ev
        self.atoms: dict[tuple[str, tuple[str, ...]], VarHistory] = {}
        self.fluents: dict[FluentKey, VarHistory] = {}
        """The histories, by atom (predicate, arguments) and by fluent."""
        self.changeable: set[tuple[str, str]] | None = set()
        self._derived = ev._derived_rules
        self._fixed: dict[tuple[int, str], bool] = {}
        """Per action (by identity) and part, whether what the part reads and
        writes is the same in every state: a matter of the part's structure alone,
        which grounding keeps (it only substitutes arguments), so it is asked once
        per action and not once per ground action."""

    def ground(
        self, steps: Sequence[PlanStep], domain: Domain
    ) -> tuple[tuple[GroundAction, ...], list[Moves]]:
        """Every step's ground action and its (shared) moves; an unknown action or a
        wrong argument list raises :class:`ExecutionError` naming the step."""
        actions = {a.name: a for a in domain.actions}
        # plans repeat actions (a robot going back and forth): ground each once, all
        # in the same initial state, and share the (frozen) result
        seen: dict[tuple[str, tuple[str, ...]], tuple[GroundAction, Moves]] = {}
        changeable = self.changeable
        named: set[str] = set()  # grounding only substitutes arguments: names stay
        keys = [
            (s.action, s.arguments if type(s.arguments) is tuple else tuple(s.arguments))
            for s in steps
        ]
        for i, key in enumerate(keys):
            if key in seen:
                continue
            step = steps[i]
            action = actions.get(step.action)
            if action is None:
                raise ExecutionError(
                    f"plan step {i} {step.text}: domain {domain.name!r} "
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
            seen[key] = (g, Moves(g))
            if changeable is not None and step.action not in named:
                named.add(step.action)
                for effect in (g.start_effect, g.end_effect):
                    names = written_names(effect) if changeable is not None else None
                    changeable = None if names is None else changeable | names  # type: ignore[operator]
        self.changeable = changeable
        found = [seen[key] for key in keys]
        return tuple([g for g, _ in found]), [m for _, m in found]

    def reads(
        self, cond: Condition, m: Moves, part: str, state: Callable[[], State]
    ) -> tuple[tuple[VarHistory, ...], Lits]:
        """The histories ``cond`` reads where the simulation is (``state()`` makes
        its state), and its literals' histories (None: not only literals), kept in
        ``m`` (with the over-all ones worth watching) when they are the same in
        every state."""
        key = (m.schema, part)
        fixed = self._fixed.get(key)
        if fixed is None:
            fixed = self._fixed[key] = reads_fixed(cond, self._derived)
        walked = fixed_reads(cond) if fixed else None
        if walked is None:
            listed, atoms = condition_vars(self.ev, cond, GROUND, state()), None
        else:
            listed, atoms = walked
        found = tuple(map(self.history, sorted(listed, key=var_key)))
        lits: Lits = None
        if fixed:
            setattr(m, part, found)
            if atoms is not None:  # every atom read has its history by now
                kept = self.atoms
                lits = (
                    tuple([kept[a.predicate, a.args] for a in atoms[0]]),
                    tuple([kept[a.predicate, a.args] for a in atoms[1]]),
                )
                setattr(m, part + "_lits", lits)
            if part == "over":
                m.watched = watched(found)
        return found, lits

    def access(self, effect: Effect, m: Moves, part: str, state: Callable[[], State]) -> Access:
        """What ``effect`` reads and writes where the simulation is, kept in ``m``
        when it is the same in every state."""
        key = (m.schema, part)
        fixed = self._fixed.get(key)
        if fixed is None:
            fixed = self._fixed[key] = writes_fixed(effect)
        access = fixed_effect_access(effect) if fixed else None
        if access is None:
            access = effect_access(self.ev, effect, state(), fixed)
        history = self.history
        # each variable written is looked up once (the written, added and deleted
        # ones are all among the writes)
        of = {var: history(var) for var, _ in access.writes}
        found = (
            access,
            tuple(map(history, access.read)),
            tuple([(of[var], kind) for var, kind in access.writes]),
            # in the writes' order (see var_key), not the sets'
            tuple([of[var] for var, _ in access.writes]),
            tuple([of[var] for var, kind in access.writes if kind == "add" and var[0] == "a"]),
            tuple([of[var] for var, kind in access.writes if kind == "del"]),
        )
        if fixed:
            setattr(m, part, found)
        return found

    def history(self, var: Var) -> VarHistory:
        """``var``'s history, made on first use. Kept by the atom's predicate and
        arguments (or the fluent's key): hashing and comparing those takes no
        Python call, while an :class:`Atom`'s equality is one."""
        if var[0] == "a":
            atom: Atom = var[1]  # type: ignore[assignment]
            try:
                return self.atoms[atom.predicate, atom.args]
            except KeyError:
                value = atom in self.initial
                hist = VarHistory(var, True, "add" if value else "del", value=value)
                self.atoms[atom.predicate, atom.args] = hist
                name = atom.predicate
        else:
            key: FluentKey = var[1]  # type: ignore[assignment]
            try:
                return self.fluents[key]
            except KeyError:
                hist = self.fluents[key] = VarHistory(var, False, "read")
                name = key[0]
        changeable = self.changeable
        hist.changeable = changeable is None or (var[0], name) in changeable
        return hist


def watched(over: Collection[VarHistory]) -> tuple[VarHistory, ...]:
    """The over-all reads some action may change (only they can be broken, and
    only they can order a happening)."""
    return tuple([var for var in over if var.changeable])
