"""What applying an effect actually changed, so a halted action can be undone safely.

An action's at-start effects are applied when it starts; when it is halted before
its end, rollback reverts what they changed, but only what is still as they left
it: another action may have changed the same facts since.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import Atom, Effect, FluentRef, FluentValue

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert

__all__ = ["EffectDelta"]


@dataclass
class EffectDelta:
    """What applying an effect actually changed, so it can be undone safely."""

    added: tuple[Atom, ...] = ()
    deleted: tuple[Atom, ...] = ()
    fluents: tuple[tuple[FluentKey, float | None, float], ...] = ()
    """(key, old value or None, new value)."""

    @classmethod
    def of(
        cls,
        evaluator: Evaluator,
        effect: Effect,
        state: State,
        bindings: Mapping[str, str],
        duration: float | None,
    ) -> EffectDelta:
        """What ``effect`` changes in ``state``; the evaluator keeps its answer for
        the knowledge's ``apply`` of the same effect on the same snapshot, which
        usually follows at once (the effect is worked out once, not twice)."""
        adds, deletes, updates = evaluator.changes(effect, state, bindings, duration, keep=True)
        if not (adds or deletes or updates):
            return cls()
        add_set = set(adds)
        return cls(
            added=tuple([a for a in add_set if a not in state]) if adds else (),
            deleted=tuple([d for d in set(deletes) - add_set if d in state]) if deletes else (),
            fluents=tuple(
                [(k, state.value(*k), v) for k, v in updates.items() if state.value(*k) != v]
            )
            if updates
            else (),
        )

    @property
    def empty(self) -> bool:
        return not (self.added or self.deleted or self.fluents)

    def undo(self, knowledge: ProblemExpert) -> None:
        """Revert each change that is still in place, in one knowledge transaction."""
        state = knowledge.state()
        with knowledge.transaction():
            for atom in self.added:
                if atom in state:
                    knowledge.remove_predicate(atom)
            for atom in self.deleted:
                if atom not in state:
                    knowledge.add_predicate(atom)
            for (name, args), old, new in self.fluents:
                if state.value(name, args) != new:
                    continue
                if old is None:
                    knowledge.remove_function(name, args)
                else:
                    knowledge.set_function(FluentValue(FluentRef(name, args), old))
