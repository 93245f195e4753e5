"""What a plan graph is made of: happenings, orderings and unexplained requirements.

An ordering says which happening (an action's start or end) must take place before
which other one, and why; a requirement nothing explains is kept as a value, so
checking a plan can name every problem at once. These are the words the builder
(:mod:`plansys_bridge.planning.plan_graph`), the behaviours and the scheduler share.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal, TypeAlias

from plansys_bridge.errors import ExecutionError

__all__ = [
    "END",
    "GROUND",
    "START",
    "Kind",
    "Ordering",
    "PlanGraphError",
    "Point",
    "UnexplainedRequirement",
    "When",
    "reason_text",
]

GROUND: Mapping[str, str] = MappingProxyType({})
"""Bindings for a ground action's conditions and effects: none, the evaluator
substituted its arguments already (passing them again only costs time)."""

Point: TypeAlias = Literal["start", "end"]
START: Point = "start"
END: Point = "end"

When: TypeAlias = Literal["at start", "over all", "at end"]
Kind: TypeAlias = Literal["causal", "threat", "effects"]


class PlanGraphError(ExecutionError):
    """A plan's requirement is explained neither by the knowledge nor by an earlier action.

    ``step`` is the index of the action in the plan, ``action`` its text, ``when``
    the condition's time specifier and ``requirement`` the unmet condition.
    """

    def __init__(self, problems: Sequence[UnexplainedRequirement]) -> None:
        self.problems = tuple(problems)
        first = self.problems[0]
        self.step = first.step
        self.action = first.action
        self.when = first.when
        self.requirement = first.requirement
        lines = [str(p) for p in self.problems[:10]]
        if len(self.problems) > 10:
            lines.append(f"... and {len(self.problems) - 10} more")
        super().__init__("plan rejected: " + "; ".join(lines))


@dataclass(frozen=True)
class UnexplainedRequirement:
    """One requirement of one action that nothing makes true when it is needed."""

    step: int
    action: str
    when: When
    requirement: str
    detail: str = ""

    def __str__(self) -> str:
        text = f"step {self.step} {self.action}: {self.when} requirement {self.requirement} "
        return text + (self.detail or "is not explained by the knowledge or an earlier action")


@dataclass(frozen=True)
class Ordering:
    """``source``'s ``source_point`` must happen before ``target``'s ``target_point``."""

    source: int
    source_point: Point
    target: int
    target_point: Point
    kind: Kind
    subject: str
    """The atom or fluent the ordering protects, e.g. ``(robot_at r1 kitchen)``."""

    @property
    def reason(self) -> str:
        return reason_text(self.source_point, self.target_point, self.kind, self.subject)


_VERBS: Mapping[Kind, str] = {
    "causal": "needs",
    "threat": "must not break",
    "effects": "conflicting effects on",
}


def reason_text(source_point: Point, target_point: Point, kind: Kind, subject: str) -> str:
    """``start->end needs (robot_at r1 kitchen)``: an ordering's reason, also written
    by the DOT view's edges without making the :class:`Ordering`."""
    return f"{source_point}->{target_point} {_VERBS[kind]} {subject}"
