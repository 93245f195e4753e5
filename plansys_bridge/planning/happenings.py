"""A plan as happenings on its timeline, for the validator.

Every durative step has a start and an end happening; a plain ``:action`` is one
instantaneous happening at its time, whose precondition is checked and whose effect
applies then (as PlanSys2's executor sees it). Happenings closer than
:data:`SAME_TIME` are simultaneous. Conditions and effects stay lifted: each
happening carries its step's bindings.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, NamedTuple

from plansys_bridge.pddl.model import (
    NO_EFFECT,
    TRUE,
    AnyAction,
    Condition,
    DurativeAction,
    Effect,
)

if TYPE_CHECKING:
    from plansys_bridge.planning.mutex import GroundParts

__all__ = ["SAME_TIME", "BoundStep", "Happening", "Point", "simultaneous"]

SAME_TIME = 1e-6
"""Happenings closer than this are simultaneous (plan files print 3-4 decimals)."""

Point = Literal["start", "end", "instant"]


class BoundStep(NamedTuple):
    """A plan step's action with its bindings, its parts as the validator sees them: a
    plain ``:action`` is one instant whose precondition is checked and whose effect
    applies then. (A named tuple: one is made per step of every plan validated.)"""

    action: AnyAction
    bindings: Mapping[str, str]

    @property
    def at_start(self) -> Condition:
        return self.action.at_start if isinstance(self.action, DurativeAction) else TRUE

    @property
    def over_all(self) -> Condition:
        act = self.action
        return act.over_all if isinstance(act, DurativeAction) else act.precondition

    @property
    def at_end(self) -> Condition:
        return self.action.at_end if isinstance(self.action, DurativeAction) else TRUE

    @property
    def start_effect(self) -> Effect:
        act = self.action
        return act.start_effect if isinstance(act, DurativeAction) else NO_EFFECT

    @property
    def end_effect(self) -> Effect:
        act = self.action
        return act.end_effect if isinstance(act, DurativeAction) else act.effect


_ORDER = {"end": 0, "instant": 1, "start": 2}
"""Ends before starts at one time: an interval closes before the next opens."""


@dataclass(slots=True)
class Happening:
    time: float
    index: int
    point: Point
    bound: BoundStep
    duration: float | None
    parts: GroundParts | None = field(default=None, compare=False, repr=False)
    """Its condition and effect with the step's arguments in place (plain actions)."""

    @property
    def bindings(self) -> Mapping[str, str]:
        return self.bound.bindings

    @property
    def condition(self) -> Condition:
        b = self.bound
        if self.point == "start":
            return b.at_start
        if self.point == "end":
            return b.at_end
        return b.over_all

    @property
    def when(self) -> str:
        return {
            "start": "at start condition",
            "end": "at end condition",
            "instant": "precondition",
        }[self.point]

    @property
    def effect(self) -> Effect:
        return self.bound.start_effect if self.point == "start" else self.bound.end_effect

    def sort_key(self) -> tuple[float, int, int]:
        return (self.time, _ORDER[self.point], self.index)


def simultaneous(happenings: list[Happening]) -> Iterator[list[Happening]]:
    """The happenings (sorted by :meth:`Happening.sort_key`) in groups of one time."""
    position = 0
    while position < len(happenings):
        group = [happenings[position]]
        position += 1
        while position < len(happenings) and happenings[position].time - group[0].time <= SAME_TIME:
            group.append(happenings[position])
            position += 1
        yield group
