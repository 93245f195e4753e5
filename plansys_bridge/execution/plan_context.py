"""The run-time state the behaviours of one running plan share.

Each action has an :class:`ActionRuntime` (which of its happenings took place, its
record, why it stopped); the :class:`PlanContext` holds them all with the hub, the
knowledge and the options, keeps the records and publishes
``ActionExecutionInfo``. Which branches are worth ticking it decides as a
:class:`~plansys_bridge.execution.branch_wakeups.BranchWakeups`.
:class:`ActionRuntime` (:mod:`plansys_bridge.execution.action_runtime`) and
:class:`EffectDelta` (what an at-start effect changed, so a halted action can be
undone; :mod:`plansys_bridge.execution.effect_delta`) are re-exported here.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution.action_runtime import ActionRuntime
from plansys_bridge.execution.branch_wakeups import BranchWakeups
from plansys_bridge.execution.effect_delta import EffectDelta
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ActionRecord
from plansys_bridge.hub.auction import ActionOutcome
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecutionInfo, ActionStatus, Topics, execution_info
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Condition
from plansys_bridge.planning.orderings import GROUND, START, Point
from plansys_bridge.planning.plan_graph import PlanGraph
from plansys_bridge.planning.requirement_text import describe_unmet

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert

__all__ = ["ActionRuntime", "EffectDelta", "PlanContext"]

log = logging.getLogger(__name__)

_INFO = Topics.ACTION_EXECUTION_INFO


class PlanContext(BranchWakeups):
    """Everything the behaviours of one running plan share.

    The executor owns it; behaviours read ``knowledge``/``evaluator`` and report
    through :meth:`action_started`, :meth:`action_finished` and friends, which keep
    the records, publish ``ActionExecutionInfo`` and wake the executor.
    """

    def __init__(
        self,
        *,
        hub: Hub,
        knowledge: ProblemExpert,
        evaluator: Evaluator,
        graph: PlanGraph,
        options: ExecutorOptions,
        plan_id: str,
        plan_index: int,
        on_info: Callable[[ActionExecutionInfo], None] | None = None,
    ) -> None:
        self.hub = hub
        self.knowledge = knowledge
        self.evaluator = evaluator
        self.graph = graph
        self.options = options
        self.plan_id = plan_id
        self.plan_index = plan_index
        self.on_info = on_info
        # Mission time is read several times per action: the clock's bound method
        # saves a call each time.
        self.now = hub.clock.now  # type: ignore[method-assign]
        self._info_heard = hub.has_audience
        self.actions: list[ActionRuntime] = []
        for i, (step, ground) in enumerate(zip(graph.steps, graph.ground, strict=True)):
            record = ActionRecord(
                text=step.text,
                plan_index=plan_index,
                step=i,
                planned_duration=step.duration,
                request_id=f"{plan_id}/{plan_index}/{i}",
            )
            self.actions.append(ActionRuntime(i, step, ground, record))
        self.draining = False
        """Set on the first failure: no further action starts."""
        self.cancelled = False
        self.halt_requested = False
        """Set after a failure with ``halt_on_failure``: the executor halts what runs."""
        self.failures: list[str] = []
        self.progress = False
        """Set whenever an action moves on; the executor ticks again while it is set."""
        self.changed = False
        """Set when a status changed since the last DOT publication."""
        self.tasks: set[asyncio.Future[Any]] = set()
        """What runs for the plan (auction clients' outcome futures, tasks): the
        executor cancels and awaits them when the plan ends."""
        self.unfinished = len(self.actions)
        BranchWakeups.__init__(self, graph)
        self._changed_steps: set[int] = set()
        self._soon: list[tuple[Callable[..., object], tuple[Any, ...]]] = []

    def soon(self, callback: Callable[..., object], *args: Any) -> None:
        """``loop.call_soon(callback, *args)`` for what a tick starts (the first
        step of each auction client): those of one tick run in one loop callback,
        in the order they were asked for, at the place in the loop's queue the first
        of them would have taken. Why: they were asked for one after another within
        the tick, so nothing ran between them anyway, and a loop callback each was
        about six Python calls per executed action."""
        pending = self._soon
        pending.append((callback, args))
        if len(pending) == 1:
            asyncio.get_running_loop().call_soon(self._run_soon)

    def _run_soon(self) -> None:
        pending, self._soon = self._soon, []
        for i, (callback, args) in enumerate(pending):
            try:
                callback(*args)
            except BaseException:
                # the loop reports it as it would have; the rest go on in a callback
                # of their own, after what was queued meanwhile
                rest = pending[i + 1 :]
                if rest:
                    self._soon = rest + self._soon
                    asyncio.get_running_loop().call_soon(self._run_soon)
                raise

    # ------------------------------------------------------------ time and wake-ups

    def now(self) -> float:  # replaced per instance by the clock's own now (see __init__)
        """Mission time (the hub's clock)."""
        return self.hub.clock.now()

    # ------------------------------------------------------------ knowledge

    def state(self) -> State:
        return self.knowledge.state()

    def holds(self, rt: ActionRuntime, cond: Condition) -> bool:
        return self.evaluator.holds(cond, self.knowledge.state(), GROUND, rt.step.duration)

    def unmet(self, rt: ActionRuntime, cond: Condition) -> str:
        """The conjuncts of ``cond`` that do not hold now, as ground PDDL text."""
        return describe_unmet(self.evaluator, cond, self.state(), GROUND, rt.step.duration)

    def reached(self, index: int, point: Point) -> bool:
        rt = self.actions[index]
        return rt.start_reached if point == START else rt.end_reached

    # ------------------------------------------------------------ reporting

    def take_changed_steps(self) -> set[int]:
        """The steps whose status may have changed since the last call (for the DOT)."""
        changed, self._changed_steps = self._changed_steps, set()
        return changed

    def publish_info(self, rt: ActionRuntime, now: float | None = None) -> None:
        """Publish the action's ``ActionExecutionInfo``; ``now``: the mission time
        the caller read already (the start time of an action that just started).
        Nothing is made when nobody would read it (no ``on_info``, no audience)."""
        self._changed_steps.add(rt.index)
        if self.on_info is None and not self._info_heard(_INFO):
            return
        rec = rt.record
        step = rt.step
        info = execution_info(
            rec.status,
            rec.start if rec.start is not None else 0.0,
            self.now() if now is None else now,
            step.text,
            step.action,
            step.arguments,
            step.duration,
            rec.completion,
            rec.message,
        )
        self.hub.publish(_INFO, info)
        if self.on_info is not None:
            try:
                self.on_info(info)
            except Exception:  # a broken observer must not break the plan
                log.exception("on_info callback %r failed", self.on_info)

    def _stop_starting(self) -> None:
        self.draining = True
        if self.options.halt_on_failure:
            self.halt_requested = True
        for rt in self.actions:
            if not rt.finished and not rt.start_reached:
                self.active.add(rt.index)

    # ------------------------------------------------------------ reporting progress

    def action_started(self, rt: ActionRuntime) -> None:
        rt.start_reached = True
        now = self.now()
        rt.record.start = now
        rt.record.status = ActionStatus.EXECUTING
        self.progress = self.changed = True
        index = rt.index
        woken = self._on_start.pop(index, None)
        if woken is not None or index in self._first_move or index in self._on_move:
            self._happened(index, woken)
        self.publish_info(rt, now)

    def action_ended(self, rt: ActionRuntime) -> None:
        rt.end_reached = True
        rt.start_delta = None  # undone only before the end (see rollback)
        if rt.record.end is None:
            rt.record.end = self.now()
        self.progress = self.changed = True
        index = rt.index
        woken = self._on_end.pop(index, None)
        if woken is not None or index in self._first_move or index in self._on_move:
            self._happened(index, woken)

    def action_executed(self, rt: ActionRuntime, outcome: ActionOutcome) -> None:
        """The performer is done (success or not); the at-end part may still wait."""
        rec = rt.record
        rec.end = self.now()
        rec.performer = outcome.performer
        rec.completion = outcome.completion
        rec.message = outcome.status
        rec.reauctioned = outcome.reauctioned
        self.progress = True

    def confirmed(self, rt: ActionRuntime, node: str) -> None:
        """A performer was confirmed for the action: its work begins (first confirm
        kept; a re-auction only changes the performer)."""
        if rt.record.confirmed is None:
            rt.record.confirmed = self.now()
        rt.record.performer = node

    def feedback(self, rt: ActionRuntime, completion: float, status: str) -> None:
        """Keep the performer's progress; publish it at most once per ``info_period``
        per action (status changes always go out, carrying the latest progress)."""
        rt.record.completion = completion
        rt.record.message = status
        now = self.now()
        if now < rt.next_feedback_info:
            return
        rt.next_feedback_info = now + self.options.info_period
        self.publish_info(rt)

    def action_finished(self, rt: ActionRuntime, success: bool) -> None:
        """The action's branch is over; settle its record (called once)."""
        if rt.finished:
            return
        rt.finished = True
        self.unfinished -= 1
        index = rt.index
        self.active.discard(index)
        if index in self.resting:
            self._stop_resting(index)
        # the branches still parked on it (on a happening it will now never reach)
        woken = self._on_start.pop(index, None)
        late = self._on_end.pop(index, None)
        if late is not None:
            woken = late if woken is None else woken + late
        if woken is not None or index in self._first_move or index in self._on_move:
            self._happened(index, woken)
        rec = rt.record
        self.progress = self.changed = True
        if success:
            rec.status = ActionStatus.SUCCEEDED
            if rec.start is None:
                rec.start = self.now()
            if rec.end is None:
                rec.end = self.now()
            self.publish_info(rt)
            return
        if rt.skipped:
            rec.message = rt.reason or rec.message
            self.publish_info(rt)  # NOT_EXECUTED stays: it never started; say why
            return
        rec.status = ActionStatus.FAILED
        rec.message = rt.reason or rec.message or "failed"
        if rt.start_reached and rec.end is None:
            rec.end = self.now()
        self._rollback(rt)
        self._stop_starting()
        self.failures.append(f"{rt.step.text}: {rec.message}")
        self.publish_info(rt)

    def action_halted(self, rt: ActionRuntime) -> None:
        """The branch was stopped from outside (cancel, halt) before it finished."""
        if rt.finished:
            return
        rt.finished = True
        self.unfinished -= 1
        self.active.discard(rt.index)
        self._stop_resting(rt.index)
        self.changed = True
        if rt.start_reached and not rt.end_reached:
            rt.record.status = ActionStatus.CANCELLED
            rt.record.message = rt.reason or "cancelled"
            if rt.record.end is None:
                rt.record.end = self.now()
            self._rollback(rt)
            self.publish_info(rt)
        else:
            rt.skipped = True
            rt.record.message = rt.reason or "not started: cancelled"
            self.publish_info(rt)

    def _rollback(self, rt: ActionRuntime) -> None:
        if not self.options.rollback_on_halt or rt.end_reached or rt.start_delta is None:
            return
        if rt.start_delta.empty:
            return
        try:
            rt.start_delta.undo(self.knowledge)
        except PlansysBridgeError as exc:
            rt.record.message += f" (its at-start effects could not be undone: {exc})"

    def track(self, task: asyncio.Future[Any]) -> None:
        self.tasks.add(task)
        task.add_done_callback(self.tasks.discard)
