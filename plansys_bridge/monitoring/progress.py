"""Progress of a mission as plain lines, one per thing that happened.

The format for logs and pipes (CI, ``| tee``): a status change of an action, the
performer that won its auction (and how many bid), each replanned plan as soon as
the executor starts it, and an action's completion (from its performer's FEEDBACK)
each time it passes a quarter (every FEEDBACK would flood a log), and a performer
that stops, fails or comes back (not its every READY and RUNNING). The live view
(:mod:`plansys_bridge.monitoring.live`) shows completion as bars instead.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from plansys_bridge.hub.messages import ActionStatus, PerformerState, PlanItem
from plansys_bridge.monitoring.watch import WatchEvent

__all__ = ["ProgressLines", "plan_lines"]

Printer = Callable[[str], None]


def plan_lines(items: Iterable[PlanItem]) -> list[str]:
    """PlanSys2's plan format, indented, one line per item (``0.000: (a x)  [5.000]``)."""
    return [f"    {item.time:.3f}: {item.action}  [{item.duration:.3f}]" for item in items]


class ProgressLines:
    """A watch listener printing one line per event worth a line.

    ``elapsed`` gives the mission time shown in brackets; ``first_plan`` says
    whether the first plan is printed too (``run`` prints it itself, with the
    planning time).
    """

    def __init__(
        self, out: Printer, elapsed: Callable[[], float], first_plan: bool = False
    ) -> None:
        self.out = out
        self.elapsed = elapsed
        self.first_plan = first_plan
        self._quarters: dict[int, int] = {}
        """id of an action's view -> the last quarter of completion printed for it."""
        self._states: dict[str, PerformerState] = {}
        """Performer -> the state it was last seen in."""

    def __call__(self, event: WatchEvent) -> None:
        t = f"[{self.elapsed():8.1f}]"
        if event.kind == "plan" and event.plan is not None:
            plan = event.plan
            if plan.replan or self.first_plan:
                what = f"replanned (plan {plan.number + 1}, " if plan.replan else "plan ("
                self.out(f"{t} {what}{len(plan.items)} actions):")
                for line in plan_lines(plan.items):
                    self.out(line)
        elif event.kind == "status" and event.action is not None:
            a = event.action
            extra = (
                f" - {a.message}"
                if a.message and a.status in (ActionStatus.FAILED, ActionStatus.CANCELLED)
                else ""
            )
            self.out(f"{t} {a.status.name:<9} {a.text}{extra}")
        elif event.kind == "feedback" and event.action is not None:
            a = event.action
            quarter = min(3, int(a.completion * 4 + 1e-9))
            if a.status == ActionStatus.EXECUTING and quarter > self._quarters.get(id(a), 0):
                self._quarters[id(a)] = quarter
                who = f" ({a.performer})" if a.performer else ""
                self.out(f"{t} {'PROGRESS':<9} {a.text} {25 * quarter} %{who}")
        elif event.kind == "performer" and event.performer is not None:
            p = event.performer
            before = self._states.get(p.name)
            self._states[p.name] = p.state
            if _worth_a_line(before, p.state):
                self.out(f"{t} {'PERFORMER':<9} {p.name} {p.state.name.lower()}")
        elif event.kind == "assigned" and event.action is not None:
            a = event.action
            bids = f"{a.bids} bid{'s' if a.bids != 1 else ''}"
            self.out(f"{t} {'ASSIGNED':<9} {a.text} -> {a.performer} ({bids})")


_WORKING = (PerformerState.READY, PerformerState.RUNNING)


def _worth_a_line(before: PerformerState | None, now: PerformerState) -> bool:
    """A performer that stopped or broke, or came back: not its every action (READY
    and RUNNING in turn), nor the first heartbeat of one that is ready."""
    if before is None:
        return now not in _WORKING
    return (before in _WORKING) != (now in _WORKING) or (before != now and now not in _WORKING)
