"""What an execution returns: per-action records and the overall result.

Typed results rather than exceptions: a failed action, a replan or a cancel are
expected outcomes a mission runner reports, not programming errors.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.planning.plan import Plan

__all__ = ["ActionRecord", "ExecutionResult", "efficiency", "efficiency_text"]


@dataclass
class ActionRecord:
    """One action of one plan as it was executed.

    ``start`` is the mission time (``hub.clock.now()``) of the at-start effects,
    ``confirmed`` when a performer was confirmed for it (its work begins; later than
    ``start`` when the performer was busy and the REQUEST had to be repeated), and
    ``end`` when the performer finished (or the action failed or was halted).
    ``plan_index`` says which plan of the result (0: the first, 1: after the first
    replan...) the action belongs to; ``step`` its index there.
    """

    text: str
    status: ActionStatus = ActionStatus.NOT_EXECUTED
    start: float | None = None
    confirmed: float | None = None
    end: float | None = None
    performer: str = ""
    message: str = ""
    completion: float = 0.0
    plan_index: int = 0
    step: int = 0
    planned_duration: float = 0.0
    request_id: str = ""
    reauctioned: int = 0
    """How many times the action was auctioned again after losing its performer."""

    @property
    def execution_time(self) -> float:
        """How long a performer worked on the action: from its confirmation to the
        end. An action no performer was confirmed for counts 0, unless it succeeded
        anyway (a template that runs it without a performer): then start to end."""
        if self.end is None:
            return 0.0
        if self.confirmed is not None:
            return max(0.0, self.end - self.confirmed)
        if self.status == ActionStatus.SUCCEEDED and self.start is not None:
            return max(0.0, self.end - self.start)
        return 0.0

    def to_dict(self) -> dict[str, Any]:
        """Plain data for JSON reports (``status`` as its PlanSys2 name)."""
        data = asdict(self)
        data["status"] = self.status.name
        data["execution_time"] = self.execution_time
        return data


@dataclass
class ExecutionResult:
    """The outcome of :meth:`Executor.execute`.

    ``status`` is one of ``succeeded``, ``failed``, ``cancelled``, ``rejected`` (the
    plan graph did not explain a requirement; ``message`` names it) or
    ``replan_failed`` (the planner found no new plan). ``plans`` lists every plan
    executed, the first one included, so ``replans == len(plans) - 1``.
    """

    success: bool
    status: str
    actions: list[ActionRecord] = field(default_factory=list)
    replans: int = 0
    plans: list[Plan] = field(default_factory=list)
    started: float = 0.0
    finished: float = 0.0
    message: str = ""
    plan_id: str = ""

    @property
    def total_time(self) -> float:
        return max(0.0, self.finished - self.started)

    @property
    def failures(self) -> int:
        """Actions that failed (a halted action counts as cancelled, not failed)."""
        return sum(1 for a in self.actions if a.status == ActionStatus.FAILED)

    def efficiency(self) -> float:
        """The paper's metric as a fraction: summed action execution time over total
        time (above 1.0 when actions ran in parallel)."""
        return efficiency(self.actions, self.total_time)

    @property
    def efficiency_percent(self) -> float:
        return 100.0 * self.efficiency()

    def to_dict(self) -> dict[str, Any]:
        """Plain data for JSON reports; plans in PlanSys2's text format."""
        return {
            "plan_id": self.plan_id,
            "success": self.success,
            "status": self.status,
            "message": self.message,
            "replans": self.replans,
            "failures": self.failures,
            "started": self.started,
            "finished": self.finished,
            "total_time_s": self.total_time,
            "efficiency_percent": self.efficiency_percent,
            "plans": [p.to_text() for p in self.plans],
            "actions": [a.to_dict() for a in self.actions],
        }

    def summary(self) -> str:
        """A readable report: outcome line, then one line per action."""
        head = (
            f"{self.status}: {len(self.actions)} actions, {self.failures} failed, "
            f"{self.replans} replans, {self.total_time:.1f} s, "
            f"efficiency {efficiency_text(self)}"
        )
        lines = [head] + ([f"  {self.message}"] if self.message else [])
        for a in self.actions:
            when = (
                f"{a.start - self.started:8.2f} -> {a.end - self.started:8.2f}"
                if a.start is not None and a.end is not None
                else f"{'-':>8}    {'-':>8}"
            )
            note = f"  ({a.message})" if a.message and a.status != ActionStatus.SUCCEEDED else ""
            lines.append(
                f"  [{a.plan_index}] {a.status.name:<12} {when}  {a.text}"
                f"{'  by ' + a.performer if a.performer else ''}{note}"
            )
        return "\n".join(lines)


def efficiency(actions: list[ActionRecord], total_time: float) -> float:
    """Summed execution time of ``actions`` divided by ``total_time`` (0 if no time)."""
    if total_time <= 0:
        return 0.0
    return sum(a.execution_time for a in actions) / total_time


def efficiency_text(result: ExecutionResult) -> str:
    """The efficiency for people: ``"183.4 %"``, or ``"n/a (no action succeeded)"``.

    Failed and halted actions count their working time too, so two robots failing
    side by side would read as 200 % efficient, which says nothing useful.
    """
    if not any(a.status == ActionStatus.SUCCEEDED for a in result.actions):
        return "n/a (no action succeeded)"
    return f"{result.efficiency_percent:.1f} %"
