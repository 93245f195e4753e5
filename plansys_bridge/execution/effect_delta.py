"""What applying an effect actually changed, so a halted action can be undone safely.

An action's at-start effects are applied when it starts; when it is halted before
its end, rollback reverts what they changed, but only what is still as they left
it: another action may have changed the same facts since.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from plansys_bridge.knowledge.state import FluentKey
from plansys_bridge.pddl.model import Atom, FluentRef, FluentValue

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
