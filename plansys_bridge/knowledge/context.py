"""What one evaluation reads, and the errors evaluating can raise.

Why a module of its own: the join solver, the derived-predicate fixpoint and the
meaning of conditions, values and effects all read facts through the same
context (base facts from the state, derived facts from the table being built or
the one cached on the state, a semi-naive round's delta tables), and they live in
separate modules below the evaluator.
"""

from __future__ import annotations

from typing import Protocol

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.state import Args, State
from plansys_bridge.pddl.model import DerivedPredicate

__all__ = ["DerivedSource", "EvalContext", "EvaluationError", "UndefinedFluentError"]


class EvaluationError(KnowledgeError):
    """A condition or effect cannot be evaluated (division by zero, no ?duration, ...)."""


class UndefinedFluentError(EvaluationError):
    """A numeric fluent was read before any value was given to it."""

    def __init__(self, name: str, args: tuple[str, ...]) -> None:
        self.fluent = (name, args)
        text = "(" + " ".join((name, *args)) + ")"
        super().__init__(f"fluent {text} is undefined")


EMPTY: frozenset[Args] = frozenset()


class DerivedSource(Protocol):
    """Where a context finds derived predicates: their rules and, per state, their facts."""

    _derived_rules: dict[str, list[DerivedPredicate]]

    def _derived_table(self, state: State) -> dict[str, frozenset[Args]]: ...


class EvalContext:
    """What one evaluation needs: the state, ?duration, and derived-fact tables."""

    __slots__ = ("delta", "derived", "duration", "ev", "state")

    def __init__(
        self,
        ev: DerivedSource,
        state: State,
        duration: float | None,
        derived: dict[str, set[Args]] | None = None,
    ) -> None:
        self.ev = ev
        self.state = state
        self.duration = duration
        self.derived = derived
        self.delta: dict[str, set[Args]] | None = None

    def tuples(self, predicate: str) -> frozenset[Args] | set[Args]:
        if predicate in self.ev._derived_rules:
            if self.derived is not None and predicate in self.derived:
                return self.derived[predicate]
            return self.ev._derived_table(self.state).get(predicate, EMPTY)
        if self.delta is not None and predicate in self.delta:
            return self.delta[predicate]
        return self.state.tuples(predicate)
