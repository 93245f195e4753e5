"""The outcome of asking a solver for a plan.

Expected outcomes (no plan exists, the solver timed out, the task uses a feature
the solver lacks) are values, not exceptions: a caller such as the executor's
replanning loop branches on :class:`PlanStatus` and shows :attr:`PlanResult.message`
to the user, which always says *why* (the solver's own words, exit status, stderr).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from plansys_bridge.planning.plan import Plan

if TYPE_CHECKING:
    from plansys_bridge.planning.validation import ValidationReport


class PlanStatus(enum.Enum):
    SOLVED = "solved"
    UNSOLVABLE = "unsolvable"
    """The solver proved (or, for incomplete solvers, says) that no plan exists."""
    TIMEOUT = "timeout"
    UNSUPPORTED = "unsupported"
    """No configured solver plans with the features this task uses."""
    ERROR = "error"
    """The solver crashed, rejected its input, or produced unreadable output."""


@dataclass(frozen=True)
class PlanResult:
    status: PlanStatus
    plan: Plan | None
    solver: str
    message: str
    elapsed_s: float
    validation: ValidationReport | None = field(default=None, compare=False)
    """Set when the planner was asked to validate the plan it got."""

    @property
    def solved(self) -> bool:
        return self.status is PlanStatus.SOLVED and self.plan is not None

    def __str__(self) -> str:
        head = f"{self.solver}: {self.status.value} in {self.elapsed_s:.3f} s"
        return f"{head}: {self.message}" if self.message else head
