"""The plan validator's state between happenings.

Most happenings of a plan only add and delete ground atoms. Building a new
:class:`~plansys_bridge.knowledge.state.State` for each (copying the touched
predicates' sets and the index) was a large part of a validation, so the validator
keeps the state it started from plus the net effect of the plain changes since, and
builds a new snapshot only when something needs one: the evaluator (quantifiers,
numeric values, derived predicates) or the end of the plan.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import Atom

__all__ = ["AtomKey", "WorkingState"]

AtomKey = tuple[str, tuple[str, ...]]
"""``("robot_at", ("r1", "kitchen"))``: a ground atom without the :class:`Atom`."""


class WorkingState:
    """A snapshot plus pending plain changes; :meth:`state` folds them in."""

    __slots__ = ("_base", "_net")

    def __init__(self, base: State) -> None:
        self._base = base
        self._net: dict[AtomKey, bool] = {}
        """Atoms changed since ``_base``: True added, False deleted (the last change)."""

    def has(self, predicate: str, args: tuple[str, ...]) -> bool:
        """Whether the atom is true now."""
        now = self._net.get((predicate, args))
        return self._base.has(predicate, args) if now is None else now

    def change(self, adds: Iterable[AtomKey], deletes: Iterable[AtomKey]) -> None:
        """Apply one happening's plain effect: its deletes, then its adds (PDDL)."""
        net = self._net
        for key in deletes:
            net[key] = False
        for key in adds:
            net[key] = True

    def state(self) -> State:
        """The current snapshot (built from the pending changes when there are any)."""
        if self._net:
            adds = [Atom(p, a) for (p, a), added in self._net.items() if added]
            deletes = [Atom(p, a) for (p, a), added in self._net.items() if not added]
            self._base = self._base.with_changes(adds=adds, deletes=deletes)
            self._net = {}
        return self._base

    def apply(
        self, adds: list[Atom], deletes: list[Atom], values: Mapping[FluentKey, float]
    ) -> None:
        """Apply changes the evaluator worked out (atoms and fluent values)."""
        self._base = self.state().with_changes(adds=adds, deletes=deletes, fluents=values)
