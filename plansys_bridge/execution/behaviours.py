"""The py_trees behaviours templates build an action's subtree from.

Each drives one :mod:`~plansys_bridge.execution.phases` phase (the logic lives
there, shared with the one-behaviour standard action of
:mod:`~plansys_bridge.execution.standard_action`). The standard subtree
(:meth:`ActionNodes.default <plansys_bridge.execution.tree_builder.ActionNodes.default>`) is::

    WaitForPredecessors(start) -> WaitAtStartReq -> ApplyAtStartEffect
      -> ReactiveSequence[CheckTimeout?, CheckOverAllReq, ExecuteAction]
      -> WaitForPredecessors(end) -> CheckAtEndReq -> ApplyAtEndEffect

The state they share lives in :mod:`plansys_bridge.execution.plan_context`.
"""

from __future__ import annotations

import asyncio

import py_trees
from py_trees.common import Status

from plansys_bridge.execution.effect_delta import EffectDelta
from plansys_bridge.execution.phases import (
    AtEndEffectPhase,
    AtEndReqPhase,
    AtStartEffectPhase,
    AtStartReqPhase,
    ExecutePhase,
    OverAllReqPhase,
    OverrunPhase,
    Phase,
    PredecessorsPhase,
)
from plansys_bridge.execution.plan_context import ActionRuntime, PlanContext
from plansys_bridge.hub.auction import ActionClient, ActionOutcome
from plansys_bridge.planning.orderings import START, Point

__all__ = [
    "ActionBehaviour",
    "ActionBranch",
    "ActionRuntime",
    "ApplyAtEndEffect",
    "ApplyAtStartEffect",
    "CheckAtEndReq",
    "CheckOverAllReq",
    "CheckTimeout",
    "EffectDelta",
    "ExecuteAction",
    "PlanContext",
    "WaitAtStartReq",
    "WaitForPredecessors",
]


class ActionBehaviour(py_trees.behaviour.Behaviour):
    """A py_trees behaviour running one phase of an action: entered on
    ``initialise``, stepped on ``update``, halted when stopped while RUNNING."""

    def __init__(self, phase: Phase, name: str | None = None) -> None:
        rt = phase.rt
        super().__init__(name or f"{phase.label} {rt.text}:{rt.index}")
        self.phase = phase
        self.ctx = phase.ctx
        self.rt = rt

    def initialise(self) -> None:
        self.phase.initialise()

    def update(self) -> Status:
        return self.phase.run()

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            self.phase.halt()


class WaitForPredecessors(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.PredecessorsPhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime, point: Point = START) -> None:
        phase = PredecessorsPhase(ctx, rt, point)
        super().__init__(phase, f"{phase.label}({point}) {rt.text}:{rt.index}")
        self.point: Point = point


class WaitAtStartReq(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.AtStartReqPhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime, timeout: float | None = None) -> None:
        self.wait = AtStartReqPhase(ctx, rt, timeout)
        super().__init__(self.wait)
        self.timeout = timeout

    @property
    def deadline(self) -> float | None:
        return self.wait.deadline


class ApplyAtStartEffect(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.AtStartEffectPhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        super().__init__(AtStartEffectPhase(ctx, rt))


class CheckOverAllReq(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.OverAllReqPhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        super().__init__(OverAllReqPhase(ctx, rt))


class ExecuteAction(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.ExecutePhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        self.execution = ExecutePhase(ctx, rt)
        super().__init__(self.execution)

    @property
    def client(self) -> ActionClient | None:
        return self.execution.client

    @property
    def task(self) -> asyncio.Future[ActionOutcome] | None:
        return self.execution.task


class CheckTimeout(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.OverrunPhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime, overrun_percentage: float) -> None:
        self.overrun = OverrunPhase(ctx, rt, overrun_percentage)
        super().__init__(self.overrun)
        self.overrun_percentage = overrun_percentage

    @property
    def deadline(self) -> float | None:
        return self.overrun.deadline


class CheckAtEndReq(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.AtEndReqPhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        super().__init__(AtEndReqPhase(ctx, rt))


class ApplyAtEndEffect(ActionBehaviour):
    """See :class:`~plansys_bridge.execution.phases.AtEndEffectPhase`."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        super().__init__(AtEndEffectPhase(ctx, rt))


class ActionBranch(py_trees.decorators.Decorator):
    """Wraps one action's subtree: records how it ended and never lets a failure
    stop the sibling actions (the executor decides what to halt)."""

    def __init__(
        self, ctx: PlanContext, rt: ActionRuntime, child: py_trees.behaviour.Behaviour
    ) -> None:
        super().__init__(name=f"{rt.text}:{rt.index}", child=child)
        self.ctx = ctx
        self.rt = rt

    def update(self) -> Status:
        status = self.decorated.status
        if status == Status.RUNNING:
            return Status.RUNNING
        self.ctx.action_finished(self.rt, status == Status.SUCCESS)
        return Status.SUCCESS

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            self.ctx.action_halted(self.rt)
