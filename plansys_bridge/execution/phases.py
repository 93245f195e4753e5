"""The steps one plan action goes through, as plain objects that py_trees can drive.

Each action of a plan goes through::

    wait for predecessors (start) -> at-start requirement -> at-start effects
      -> [duration overrun?, over-all requirement, execution] re-checked while it runs
      -> wait for predecessors (end) -> at-end requirement -> at-end effects

A phase holds the logic of one of these steps and nothing of py_trees: the
behaviours templates assemble (:mod:`plansys_bridge.execution.behaviours`) each
drive one phase, and the standard action (:mod:`plansys_bridge.execution.standard_action`)
drives all of them from a single behaviour, so a plan of thousands of actions does
not pay eleven py_trees behaviours (each with its uuid, logger and tick generator)
per action. Both share this code, so both behave the same.

Phases never poll on a timer of their own: whatever can change their answer (a
performer's FINISH, a knowledge change, a deadline registered with
:meth:`PlanContext.schedule`) wakes the executor, which ticks the tree again.
They read the knowledge through snapshots and change it only through
``ProblemExpert.apply`` (atomic), so the knowledge never holds half an effect.
"""

from __future__ import annotations

import asyncio
from functools import partial

from py_trees.common import Status

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution.effect_delta import EffectDelta
from plansys_bridge.execution.plan_context import ActionRuntime, PlanContext
from plansys_bridge.execution.waits import (
    at_start_deadline,
    wait_at_start_req,
    wait_for_predecessors,
)
from plansys_bridge.hub.auction import ActionClient, ActionOutcome
from plansys_bridge.pddl.model import Condition
from plansys_bridge.planning.orderings import GROUND, START, Point

__all__ = [
    "AtEndEffectPhase",
    "AtEndReqPhase",
    "AtStartEffectPhase",
    "AtStartReqPhase",
    "ExecutePhase",
    "OverAllReqPhase",
    "OverrunPhase",
    "Phase",
    "PredecessorsPhase",
    "apply_at_end_effect",
    "apply_at_start_effect",
    "check_at_end_req",
    "check_over_all_req",
]


class Phase:
    """One step of an action: ``initialise`` when it is entered, ``run`` on each
    tick until it is no longer RUNNING, ``halt`` when it is stopped from outside.
    Errors raised by the knowledge fail the action with their message."""

    label = "Action"
    enters = False
    """Whether ``initialise`` does anything, so the standard action calls it only
    for the phases that need it (set for each subclass from its definition)."""

    def __init_subclass__(cls) -> None:
        super().__init_subclass__()
        cls.enters = cls.initialise is not Phase.initialise

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        self.ctx = ctx
        self.rt = rt

    def initialise(self) -> None:
        """Called once when the step is entered (again when it is re-entered)."""

    def run(self) -> Status:
        try:
            return self.step()
        except PlansysBridgeError as exc:
            self.rt.reason = f"{self.label}: {exc}"
            return Status.FAILURE

    def step(self) -> Status:  # pragma: no cover - every subclass implements it
        raise NotImplementedError

    def halt(self) -> None:
        """Called when the step is stopped before it ended."""

    def fail(self, reason: str) -> Status:
        self.rt.reason = reason
        return Status.FAILURE


class PredecessorsPhase(Phase):
    """Wait until every happening this action's ``point`` depends on took place.

    ``point="start"``: before the action starts (PlanSys2's WAIT_PREV_ACTIONS);
    ``point="end"``: before its at-end effects (PlanSys2's CHECK_PREV_ACTIONS).
    Fails when a predecessor stopped without reaching that happening, and (for the
    start) once the plan is stopping, so nothing new starts after a failure.
    """

    label = "WaitForPredecessors"

    def __init__(self, ctx: PlanContext, rt: ActionRuntime, point: Point = START) -> None:
        super().__init__(ctx, rt)
        self.point: Point = point
        self.waits = ctx.graph.waits(rt.index, point)
        self._next = 0

    def step(self) -> Status:
        status, self._next = wait_for_predecessors(
            self.ctx, self.rt, self.point, self.waits, self._next
        )
        return status


class AtStartReqPhase(Phase):
    """Wait for the at-start requirement; fail after ``timeout`` mission seconds
    (PlanSys2 #218 waits forever). ``timeout=None`` waits forever."""

    label = "WaitAtStartReq"

    def __init__(self, ctx: PlanContext, rt: ActionRuntime, timeout: float | None = None) -> None:
        super().__init__(ctx, rt)
        self.timeout = timeout
        self.deadline: float | None = None
        self._waiting = False

    def initialise(self) -> None:
        self.deadline = None
        self._waiting = False

    def step(self) -> Status:
        ctx, rt = self.ctx, self.rt
        if not self._waiting:
            if not (ctx.draining or ctx.cancelled) and ctx.holds(rt, rt.ground.at_start):
                return Status.SUCCESS
            # A wait begins: its deadline is registered only now (a requirement that
            # holds at once waits for nothing, and a deadline registered for it
            # anyway woke the executor for nothing when it came)
            self._waiting = True
            self.deadline = at_start_deadline(ctx, rt, self.timeout)
        return wait_at_start_req(ctx, rt, self.deadline, self.timeout)


class AtStartEffectPhase(Phase):
    """Apply the at-start effects (atomically) and mark the action started."""

    label = "ApplyAtStartEffect"

    def step(self) -> Status:
        return apply_at_start_effect(self.ctx, self.rt)


def apply_at_start_effect(ctx: PlanContext, rt: ActionRuntime) -> Status:
    """:class:`AtStartEffectPhase`'s step, which keeps no state: the standard action
    calls it without making a phase object."""
    # apply() says what the effect changed, net, worked out under the same lock as
    # the change: that is what a halt undoes (an effect that changes nothing
    # changes neither the knowledge's version nor its subscribers)
    applied = ctx.knowledge.apply(rt.ground.start_effect, GROUND, rt.step.duration)
    rt.start_delta = EffectDelta(applied.added, applied.deleted, applied.fluents)
    ctx.action_started(rt)
    return Status.SUCCESS


class OverAllReqPhase(Phase):
    """The over-all requirement, re-checked on every tick while the action runs;
    failing halts the action (its performer gets a CANCEL)."""

    label = "CheckOverAllReq"

    def step(self) -> Status:
        return check_over_all_req(self.ctx, self.rt)


def check_over_all_req(ctx: PlanContext, rt: ActionRuntime) -> Status:
    """:class:`OverAllReqPhase`'s step (stateless, see :func:`apply_at_start_effect`)."""
    if ctx.holds(rt, rt.ground.over_all):
        return Status.SUCCESS
    return _unmet(ctx, rt, rt.ground.over_all, "over all requirement {} no longer holds")


class ExecutePhase(Phase):
    """Hand the action to a performer through the auction and follow it.

    ``initialise`` starts an :class:`ActionClient` (``start(soon=True)``:
    its first REQUEST goes out where a task running it would have sent it, after
    the tick) and keeps the future of its outcome; the end of that future wakes the
    executor, so the next tick sees the outcome at once. Halting (over-all
    violation, timeout, cancel) cancels the client, which sends CANCEL to the
    performer.

    No task runs the client: its work is driven by hub messages and its timer, and a
    task per action cost a task object, a step to start it, a wake-up when the
    outcome was set and a done-callback round on top of the future it awaited.
    """

    label = "ExecuteAction"

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        self.ctx = ctx  # Phase.__init__ inlined: one per executed action
        self.rt = rt
        self.client: ActionClient | None = None
        self.task: asyncio.Future[ActionOutcome] | None = None
        """The outcome future (a future, not a task; the name is the executor's)."""

    def initialise(self) -> None:
        ctx, rt = self.ctx, self.rt
        client = self.client = rt.client = ActionClient(
            ctx.hub,
            rt.step.action,
            rt.step.arguments,
            request_id=rt.record.request_id,
            policy=ctx.options.auction,
        )
        # partials, not lambdas: a callback is then one Python call, not two. The end
        # is told by the client as it settles the future (settled_cb), not by a done
        # callback of the future, which the loop would schedule as a call of its own;
        # the first step goes with the others of this tick (PlanContext.soon).
        future = self.task = client.start(
            partial(ctx.feedback, rt),
            confirm_cb=partial(ctx.confirmed, rt),
            soon=True,
            settled_cb=self._ended,
            call_soon=ctx.soon,
        )
        ctx.tasks.add(future)  # as PlanContext.track does, without a done callback

    def _ended(self) -> None:
        ctx = self.ctx
        if self.task is not None:
            ctx.tasks.discard(self.task)
        ctx.resume(self.rt.index)
        ctx.wake()

    def step(self) -> Status:
        task = self.task
        if task is None:
            return Status.RUNNING
        if not task.done():
            self.ctx.rest(self.rt)
            return Status.RUNNING
        if task.cancelled():
            return self.fail("execution task cancelled")
        exc = task.exception()
        if exc is not None:
            return self.fail(f"execution failed: {exc!r}")
        outcome = task.result()
        # the runtime lets its ended client go (its cycles were broken as it ended):
        # a plan of thousands of actions would otherwise keep each one's client, its
        # future and callbacks alive until the plan ends, for the cyclic collector
        # to go through again and again
        self.rt.client = None
        self.ctx.action_executed(self.rt, outcome)
        if outcome.success:
            return Status.SUCCESS
        return self.fail(outcome.status or "performer reported failure")

    def halt(self) -> None:
        if self.task is not None and not self.task.done():
            assert self.client is not None
            self.client.cancel()
            self.rt.record.end = self.ctx.now()
            self.rt.record.performer = self.client.performer or self.rt.record.performer


class OverrunPhase(Phase):
    """Fail when the action runs longer than its planned duration plus
    ``overrun_percentage`` percent (measured from its start)."""

    label = "CheckTimeout"

    def __init__(self, ctx: PlanContext, rt: ActionRuntime, overrun_percentage: float) -> None:
        super().__init__(ctx, rt)
        self.overrun_percentage = overrun_percentage
        self.deadline: float | None = None

    def initialise(self) -> None:
        start = self.rt.record.start if self.rt.record.start is not None else self.ctx.now()
        if self.rt.step.duration > 0:
            self.deadline = start + self.rt.step.duration * (1.0 + self.overrun_percentage / 100.0)
            self.ctx.schedule(self.deadline, self.rt.index)

    def step(self) -> Status:
        if self.deadline is not None and self.ctx.now() >= self.deadline:
            return self.fail(
                f"overran its planned duration {self.rt.step.duration:g} s "
                f"by more than {self.overrun_percentage:g} %"
            )
        return Status.SUCCESS


class AtEndReqPhase(Phase):
    """The at-end requirement must hold when the action ends."""

    label = "CheckAtEndReq"

    def step(self) -> Status:
        return check_at_end_req(self.ctx, self.rt)


def check_at_end_req(ctx: PlanContext, rt: ActionRuntime) -> Status:
    """:class:`AtEndReqPhase`'s step (stateless, see :func:`apply_at_start_effect`)."""
    if ctx.holds(rt, rt.ground.at_end):
        return Status.SUCCESS
    return _unmet(ctx, rt, rt.ground.at_end, "at end requirement {} does not hold")


def _unmet(ctx: PlanContext, rt: ActionRuntime, cond: Condition, why: str) -> Status:
    """Fail the action: ``why`` with the part of ``cond`` that does not hold."""
    rt.reason = why.format(ctx.unmet(rt, cond))
    return Status.FAILURE


class AtEndEffectPhase(Phase):
    """Apply the at-end effects (atomically) and mark the action ended."""

    label = "ApplyAtEndEffect"

    def step(self) -> Status:
        return apply_at_end_effect(self.ctx, self.rt)


def apply_at_end_effect(ctx: PlanContext, rt: ActionRuntime) -> Status:
    """:class:`AtEndEffectPhase`'s step (stateless, see :func:`apply_at_start_effect`)."""
    ctx.knowledge.apply(rt.ground.end_effect, GROUND, rt.step.duration)
    ctx.action_ended(rt)
    return Status.SUCCESS
