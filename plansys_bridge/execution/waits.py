"""The two waiting steps of an action as plain functions of their state.

Waiting for predecessors and for the at-start requirement are the only steps
before the run that keep state (how far through its predecessors the action got;
when its at-start wait gives up). As functions of that state they serve both the
phase objects templates assemble (:mod:`plansys_bridge.execution.phases`) and the
standard action (:mod:`plansys_bridge.execution.standard_action`), which keeps the
state in its own fields instead of making two phase objects per action.
"""

from __future__ import annotations

from collections.abc import Sequence

from py_trees.common import Status

from plansys_bridge.execution.plan_context import ActionRuntime, PlanContext
from plansys_bridge.planning.orderings import START, Point

__all__ = ["at_start_deadline", "wait_at_start_req", "wait_for_predecessors"]

_SUCCESS = Status.SUCCESS
_RUNNING = Status.RUNNING
_FAILURE = Status.FAILURE


def wait_for_predecessors(
    ctx: PlanContext,
    rt: ActionRuntime,
    point: Point,
    waits: Sequence[tuple[int, Point]],
    first: int,
) -> tuple[Status, int]:
    """Whether every happening ``rt``'s ``point`` waits on took place, and the index
    in ``waits`` to look from next time (those before it took place already).

    ``point="start"``: before the action starts (PlanSys2's WAIT_PREV_ACTIONS);
    ``point="end"``: before its at-end effects (PlanSys2's CHECK_PREV_ACTIONS).
    Fails when a predecessor stopped without reaching that happening, and (for the
    start) once the plan is stopping, so nothing new starts after a failure. A
    branch left waiting is parked until the happening it waits for takes place
    (:meth:`PlanContext.park_on`).
    """
    if point == START and (ctx.draining or ctx.cancelled):
        rt.skipped = True
        rt.reason = "not started: the plan stopped after " + (
            ctx.failures[0] if ctx.failures else "a cancel"
        )
        return _FAILURE, first
    actions = ctx.actions
    for n in range(first, len(waits)):
        j, other_point = waits[n]
        other = actions[j]
        if not (other.start_reached if other_point == START else other.end_reached):
            if other.finished:
                if point == START:
                    rt.skipped = True
                rt.reason = f"predecessor {other.step.text} stopped before its {other_point}"
                return _FAILURE, n
            ctx.park_on(rt, j, other_point)
            return _RUNNING, n
    return _SUCCESS, len(waits)


def at_start_deadline(ctx: PlanContext, rt: ActionRuntime, timeout: float | None) -> float | None:
    """On entering the at-start wait: the mission time it gives up at (None: never),
    registered with the context so a tick comes then."""
    if timeout is None:
        return None
    deadline = ctx.now() + timeout
    ctx.schedule(deadline, rt.index)
    return deadline


def wait_at_start_req(
    ctx: PlanContext, rt: ActionRuntime, deadline: float | None, timeout: float | None
) -> Status:
    """Wait for the at-start requirement; fail once ``deadline`` passed (PlanSys2
    #218 waits forever)."""
    if ctx.draining or ctx.cancelled:
        rt.skipped = True
        rt.reason = "not started: the plan is stopping"
        return _FAILURE
    if ctx.holds(rt, rt.ground.at_start):
        return _SUCCESS
    if deadline is not None and ctx.now() >= deadline:
        unmet = ctx.unmet(rt, rt.ground.at_start)
        rt.reason = f"at start requirement {unmet} did not hold within {timeout:g} s"
        return _FAILURE
    return _RUNNING
