"""Applying an effect to the knowledge: what the executor does twice per action.

Why it is built this way:

* What an effect does is worked out by the evaluator and checked against the
  domain and the objects (:mod:`.admission`) before anything changes; the change is
  then one atomic step with one notice (:mod:`.changes`).
* An effect of ground facts only (a ground action's) changes the same facts in
  every state, so it is prepared once per effect object (:class:`FactChange`): its
  admitted facts, what applying it reports, and what it does to each predicate's
  set of the snapshot, all for the usual case (every fact it deletes is there,
  every one it adds is not). Plans repeat ground actions (a robot going round), and
  applying one again is then a look-up, the check of the usual case and the change
  itself, in one Python call with the fact table's: the calls and objects of the
  general way were most of what an executed action cost the knowledge.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from plansys_bridge.knowledge.admission import Admission
from plansys_bridge.knowledge.changes import (
    EMPTY_SET,
    AppliedEffect,
    ChangeTracker,
    KnowledgeChange,
    applied_effect,
    log,
    net_change,
)
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.grounding import effect_facts
from plansys_bridge.knowledge.state import Args, State
from plansys_bridge.pddl.model import Atom, Effect

__all__ = ["EffectApplier", "FactChange"]

_APPLIED_LIMIT = 100_000
"""Effects whose admitted facts :meth:`EffectApplier.apply` remembers; past it, new
ones are checked every time (until the objects change)."""


class FactChange:
    """An effect of facts only, admitted, with what applying it does in the usual
    case (every fact it deletes is there, every fact it adds is not), worked out once.

    Why: a ground action's effects are applied once per step and plans repeat
    ground actions; nearly always they are in the usual case. Then the net change,
    the notice's sets (built from dicts, in the order the general way builds them)
    and the :class:`AppliedEffect` are those kept here, which are immutable and
    handed out again instead of being made anew; and each predicate's new set of
    arguments is its old one with ``flips`` toggled (one symmetric difference per
    predicate instead of one set operation per fact).
    """

    __slots__ = (
        "added_facts",
        "adds",
        "applied",
        "came",
        "deletes",
        "effect",
        "flips",
        "fresh",
        "gone",
        "removed_facts",
    )

    def __init__(self, effect: object, deletes: list[Atom], adds: list[Atom]) -> None:
        self.effect = effect
        self.deletes = deletes
        self.adds = adds
        went = dict.fromkeys(deletes)
        come = dict.fromkeys(adds)
        removed, added = net_change(went, come)
        self.applied = AppliedEffect(tuple(added), tuple(removed), ())
        self.added_facts: frozenset[Atom] = frozenset(added) if added else EMPTY_SET
        self.removed_facts: frozenset[Atom] = frozenset(removed) if removed else EMPTY_SET
        self.gone = tuple(went)
        self.came = tuple(come)
        self.fresh = self.applied.added
        """The facts it adds and does not delete (those it adds, net): not there in
        the usual case."""
        # Per predicate, the arguments the usual case toggles (the deleted ones
        # go, the added ones come, one both deleted and added stays), in the order
        # State.with_facts first adds the predicates (a new one goes to the end of
        # the index, whose order is the order predicates() lists them in); a
        # predicate whose arguments do not move is left out.
        toggled: dict[str, set[Args]] = {}
        for atom in (*come, *went):
            if atom.predicate in toggled:
                toggled[atom.predicate] ^= {atom.args}
            else:
                toggled[atom.predicate] = {atom.args}
        self.flips = tuple([(p, frozenset(args)) for p, args in toggled.items() if args])


class EffectApplier(ChangeTracker):
    """:meth:`apply` for the knowledge base (see module docs)."""

    evaluator: Evaluator
    _admit: Admission

    def __init__(self, constants: Mapping[str, str]) -> None:
        super().__init__(constants)
        self._applied: dict[int, FactChange] = {}
        """Effects of facts only applied before, their facts admitted, by the
        effect's id, for as long as the objects do not change (the instance table's
        write count is ``_applied_at``)."""
        self._applied_at = -1

    def apply(
        self,
        effect: Effect,
        bindings: Mapping[str, str] | None = None,
        duration: float | None = None,
    ) -> AppliedEffect:
        """Apply an effect (PDDL semantics) as one validated, atomic change, and
        say what it changed: the executor keeps that to undo an at-start effect
        when the action is halted (worked out here, where it is known anyway,
        instead of from a snapshot read before).

        What the effect does is worked out by the evaluator. Everything is
        checked before anything changes. An effect of facts only (no bindings),
        outside a transaction, is prepared once (:class:`FactChange`) and then
        applied the short way: the prepared change in the usual case, else
        :meth:`_swap_facts`."""
        with self._lock:
            version = self._instances.writes
            if bindings or self._depth:
                return self._apply_general(effect, bindings, duration, version)
            if version != self._applied_at:
                self._applied.clear()
                self._applied_at = version
            try:
                known = self._applied[id(effect)]
            except KeyError:
                known = None
            if known is None or known.effect is not effect:
                known = self._prepare(effect, version)
                if known is None:
                    return self._apply_general(effect, bindings, duration, version)
            # The usual case, checked on the fact table (the snapshot holds the same
            # facts): the new snapshot first (it touches nothing), then the table.
            state = self._state
            if known.flips:
                index = state._index
                new_index = dict(index)
                for predicate, flip in known.flips:
                    if predicate in index:
                        tuples = index[predicate] ^ flip
                        if tuples:
                            new_index[predicate] = tuples
                        else:
                            del new_index[predicate]
                    else:  # none of it yet: its arguments are the flip itself
                        new_index[predicate] = flip
                # State._build, inlined (two of these per executed action)
                new = State.__new__(State)
                new._index = new_index
                new._facts = None
                new._fluents = state._fluents
                new._flat = state._flat
                new._objects = state._objects
                new._cache = None
                new._object_cache = state._object_cache
                state = new
            if self._facts.exchange(known.gone, known.came, known.fresh, None):
                self._state = self._published = state
                applied = known.applied
                added_facts = known.added_facts
                removed_facts = known.removed_facts
            else:
                state, applied, added_facts, removed_facts = self._swap_facts(
                    known.deletes, known.adds
                )
            if not (added_facts or removed_facts):
                return applied
            self.version += 1
            # KnowledgeChange._made, inlined: its fields written in its order
            change = object.__new__(KnowledgeChange)
            fields = change.__dict__
            fields["version"] = self.version
            fields["reason"] = "apply"
            fields["added_instances"] = {}
            fields["removed_instances"] = {}
            fields["added_facts"] = added_facts
            fields["removed_facts"] = removed_facts
            fields["changed_fluents"] = {}
            fields["removed_fluents"] = EMPTY_SET
            fields["goal_changed"] = False
            fields["goal"] = self._goal
            fields["state"] = state
            # _notify, inlined
            for callback in list(self._subscribers):
                try:
                    callback(change)
                except Exception:  # a broken subscriber must not break the knowledge
                    log.exception("knowledge subscriber %r failed", callback)
            return applied

    def _prepare(self, effect: Effect, version: int) -> FactChange | None:
        """The effect's :class:`FactChange`, remembered while there is room; None
        when it does more than add and delete ground facts. Its facts are admitted
        here (adds first), so a bad one raises before anything changes; the
        effect's own atoms are read (admission makes the facts stored), not the
        evaluator's copies of them (:meth:`Evaluator.plain_changes`)."""
        parts = effect_facts(effect)
        if parts is None:
            return None
        adds, deletes = parts
        checked_adds = self._admit.facts(adds, version) if adds else []
        checked_deletes = self._admit.facts(deletes, version) if deletes else []
        known = FactChange(effect, checked_deletes, checked_adds)
        if len(self._applied) < _APPLIED_LIMIT:
            self._applied[id(effect)] = known
        return known

    def _apply_general(
        self,
        effect: Effect,
        bindings: Mapping[str, str] | None,
        duration: float | None,
        version: int,
    ) -> AppliedEffect:
        """:meth:`apply` of any effect, inside a transaction too (the lock held)."""
        adds: Sequence[Atom]
        deletes: Sequence[Atom]
        adds, deletes, updates = self.evaluator.changes(effect, self._state, bindings, duration)
        checked_adds = self._admit.facts(adds, version) if adds else []
        checked_deletes = self._admit.facts(deletes, version) if deletes else []
        for key in updates:
            self._admit.fluent(*key)
        applied = applied_effect(self._state, checked_adds, checked_deletes, updates)
        with self._change("apply"):
            self._facts.discard_many(checked_deletes)
            self._facts.set_many(checked_adds, None)
            for key, number in updates.items():
                self._fluents.set(key, number)
            self._state = self._state.with_changes(
                adds=checked_adds, deletes=checked_deletes, fluents=updates
            )
        return applied
