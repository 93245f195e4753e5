"""One plan action's progress while its plan runs (:class:`ActionRuntime`).

The behaviours of a plan, the context they share and the executor all read and
write it: which of the action's happenings took place, its record, why it stopped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from plansys_bridge.execution.effect_delta import EffectDelta
from plansys_bridge.execution.results import ActionRecord
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.knowledge.evaluation import GroundAction
from plansys_bridge.planning.plan import PlanStep

__all__ = ["ActionRuntime"]


@dataclass
class ActionRuntime:
    """One action's progress: which of its happenings took place, and why it stopped."""

    index: int
    step: PlanStep
    ground: GroundAction
    record: ActionRecord
    start_reached: bool = False
    end_reached: bool = False
    finished: bool = False
    skipped: bool = False
    """Never started because the plan stopped (a failure, a cancel)."""
    reason: str = ""
    start_delta: EffectDelta | None = None
    client: ActionClient | None = None
    next_feedback_info: float = -math.inf
    """Mission time before which a FEEDBACK updates the record without an info."""
    may_rest: bool = False
    """The branch is the standard subtree: while its performer works it needs a tick
    only when the performer ends, a deadline passes or what its over-all reads changes."""

    @property
    def text(self) -> str:
        """The step's text, ``(move r1 a b)`` (kept by the step)."""
        return self.step.text
