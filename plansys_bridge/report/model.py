"""What the pictures and ``summary.json`` are drawn from: a run as rows of actions.

Built from a :class:`~plansys_bridge.monitoring.watch.MissionWatch`, so a run just
finished and a recording read back give the same report. Times are mission seconds
from the start of the run; planned times are the plan's times shifted to when the
executor started that plan.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.monitoring.watch import MissionWatch

__all__ = ["ActionRow", "PlanRow", "ReportError", "RunReport"]


class ReportError(PlansysBridgeError):
    """A report that cannot be read from its source or written."""


@dataclass(frozen=True)
class ActionRow:
    text: str
    plan: int
    """Which plan it belongs to: 0 the first, 1 after the first replan..."""
    performer: str
    status: str
    planned_start: float
    planned_end: float
    start: float | None
    end: float | None
    message: str = ""

    @property
    def executed(self) -> float:
        if self.start is None or self.end is None:
            return 0.0
        return max(0.0, self.end - self.start)


@dataclass(frozen=True)
class PlanRow:
    number: int
    started: float
    text: str


@dataclass
class RunReport:
    """One run: its outcome, its plans and every action of every plan."""

    name: str
    status: str
    success: bool
    message: str = ""
    total_time: float = 0.0
    actions: list[ActionRow] = field(default_factory=list)
    plans: list[PlanRow] = field(default_factory=list)
    dots: dict[str, str] = field(default_factory=dict)
    """DOT graph name (``plan-1/0``) -> the last DOT text published for it."""

    @classmethod
    def from_watch(
        cls,
        watch: MissionWatch,
        *,
        name: str,
        status: str,
        success: bool,
        message: str = "",
        started: float = 0.0,
        finished: float | None = None,
    ) -> RunReport:
        """The report of what ``watch`` saw; times become relative to ``started``."""

        def rel(t: float | None) -> float | None:
            return None if t is None else t - started

        report = cls(name, status, success, message, dots=dict(watch.dots))
        last = started
        for plan in watch.plans:
            base = plan.stamp - started
            text = "\n".join(f"{i.time:.3f}: {i.action}  [{i.duration:.3f}]" for i in plan.items)
            report.plans.append(PlanRow(plan.number, base, text))
            for view in plan.actions:
                report.actions.append(
                    ActionRow(
                        text=view.text,
                        plan=plan.number,
                        performer=view.performer,
                        status=view.status.name,
                        planned_start=base + view.planned_start,
                        planned_end=base + view.planned_start + view.planned_duration,
                        start=rel(view.start),
                        end=rel(view.end),
                        message=view.message,
                    )
                )
                last = max(last, view.end or last, view.start or last)
        end = finished if finished is not None else last
        report.total_time = max(0.0, end - started)
        return report

    @property
    def replans(self) -> list[float]:
        """When each replanned plan started."""
        return [p.started for p in self.plans if p.number > 0]

    @property
    def performers(self) -> list[str]:
        return sorted({a.performer for a in self.actions if a.performer})

    def efficiency_percent(self) -> float | None:
        """Executed action time over total time; None when no action succeeded."""
        if self.total_time <= 0 or not any(
            a.status == ActionStatus.SUCCEEDED.name for a in self.actions
        ):
            return None
        return 100.0 * sum(a.executed for a in self.actions) / self.total_time

    def summary(self) -> dict[str, Any]:
        """``summary.json``: outcome, counts, per-performer time, every action."""
        by_status: dict[str, int] = {}
        for a in self.actions:
            by_status[a.status] = by_status.get(a.status, 0) + 1
        busy = {p: 0.0 for p in self.performers}
        for a in self.actions:
            if a.performer:
                busy[a.performer] += a.executed
        efficiency = self.efficiency_percent()
        return {
            "mission": self.name,
            "status": self.status,
            "success": self.success,
            "message": self.message,
            "total_time_s": round(self.total_time, 3),
            "plans": len(self.plans),
            "replans": len(self.replans),
            "replan_times_s": [round(t, 3) for t in self.replans],
            "actions": len(self.actions),
            "actions_by_status": by_status,
            "efficiency_percent": None if efficiency is None else round(efficiency, 2),
            "performer_busy_s": {p: round(t, 3) for p, t in busy.items()},
            "plan_texts": [p.text for p in self.plans],
            "records": [asdict(a) for a in self.actions],
        }
