"""The run-time state the behaviours of one running plan share.

Each action has an :class:`ActionRuntime` (which of its happenings took place, its
record, why it stopped); the :class:`PlanContext` holds them all with the hub, the
knowledge and the options, keeps the records, publishes ``ActionExecutionInfo``
and decides which branches are worth ticking. :class:`EffectDelta` (what an
at-start effect changed, so a halted action can be undone) lives in
:mod:`plansys_bridge.execution.effect_delta` and is re-exported here.
"""

from __future__ import annotations

import asyncio
import heapq
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution.effect_delta import EffectDelta
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ActionRecord
from plansys_bridge.hub.auction import ActionClient, ActionOutcome
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecutionInfo, ActionStatus, Topics, execution_info
from plansys_bridge.knowledge.evaluation import Evaluator, GroundAction
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Atom, Condition, FluentRef
from plansys_bridge.pddl.walkers import Collector
from plansys_bridge.planning.orderings import GROUND, START, Point
from plansys_bridge.planning.plan import PlanStep
from plansys_bridge.planning.plan_graph import PlanGraph
from plansys_bridge.planning.requirement_text import describe_unmet

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import KnowledgeChange, ProblemExpert

__all__ = ["ActionRuntime", "EffectDelta", "PlanContext"]

log = logging.getLogger(__name__)


class _Reads(Collector):
    """Predicate and function names a condition reads; ``derived`` is set when it
    reads a derived predicate (whose inputs are not named in the condition)."""

    kinds = ("condition", "expression")

    def __init__(self, derived: frozenset[str]) -> None:
        self.derived_names = derived
        self.names: set[str] = set()
        self.derived = False

    def walk_atom(self, node: Atom) -> None:
        self.names.add(node.predicate)
        self.derived = self.derived or node.predicate in self.derived_names

    def walk_fluent_ref(self, node: FluentRef) -> None:
        self.names.add(node.name)


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


class PlanContext:
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
        self.dependents: list[set[int]] = graph.dependents()
        """For each action, the actions with a start or end wait on it."""
        self.active: set[int] = set(graph.roots())
        """Branches worth ticking: not parked waiting for a predecessor."""
        self.resting: set[int] = set()
        """Branches whose performer works and that nothing has touched since."""
        self._reads: dict[int, frozenset[str] | None] = {}
        self._reads_of: dict[int, tuple[Condition, frozenset[str] | None]] = {}
        self._derived: frozenset[str] | None = None
        self._readers: dict[str, set[int]] = {}
        """For each name some resting branch's over-all reads, those branches: a
        change then finds the branches it wakes by its names, whatever the number
        of resting branches."""
        self.unfinished = len(self.actions)
        self._deadlines: list[tuple[float, int]] = []
        """(mission time, index of the action to wake or -1) as a heap."""
        self._wake: Callable[[], None] = lambda: None
        self._changed_steps: set[int] = set()

    # ------------------------------------------------------------ time and wake-ups

    def now(self) -> float:  # replaced per instance by the clock's own now (see __init__)
        """Mission time (the hub's clock)."""
        return self.hub.clock.now()

    def wake(self) -> None:
        """Ask for a tick as soon as possible (safe from the loop's thread only)."""
        self._wake()

    def bind_wake(self, wake: Callable[[], None]) -> None:
        self._wake = wake

    def schedule(self, deadline: float, owner: int | None = None) -> None:
        """Ask for a tick at mission time ``deadline``; a resting ``owner`` (action
        index) is woken for it. Only the standard branches rest, and only their own
        deadlines (an overrun) concern them, so a deadline passing wakes its owner,
        not every resting branch (a plan with an at-start timeout per action would
        otherwise tick every running action each time one of them passes)."""
        heapq.heappush(self._deadlines, (deadline, -1 if owner is None else owner))

    def next_deadline(self) -> float | None:
        """The earliest deadline not yet taken by :meth:`pass_deadlines`."""
        return self._deadlines[0][0] if self._deadlines else None

    def pass_deadlines(self) -> None:
        """Drop the deadlines that have come, waking their resting owners."""
        now = self.now()
        while self._deadlines and self._deadlines[0][0] <= now:
            _deadline, owner = heapq.heappop(self._deadlines)
            if owner >= 0:
                self.resume(owner)

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

    def publish_info(self, rt: ActionRuntime) -> None:
        self._changed_steps.add(rt.index)
        rec = rt.record
        step = rt.step
        info = execution_info(
            rec.status,
            rec.start if rec.start is not None else 0.0,
            self.now(),
            rt.text,
            step.action,
            step.arguments,
            step.duration,
            rec.completion,
            rec.message,
        )
        self.hub.publish(Topics.ACTION_EXECUTION_INFO, info)
        if self.on_info is not None:
            try:
                self.on_info(info)
            except Exception:  # a broken observer must not break the plan
                log.exception("on_info callback %r failed", self.on_info)

    # ------------------------------------------------------------ which branches to tick

    def activate(self, index: int) -> None:
        if not self.actions[index].finished:
            self.active.add(index)

    def park(self, index: int) -> None:
        """Stop ticking a branch until one of its predecessors moves on."""
        self.active.discard(index)

    def rest(self, rt: ActionRuntime) -> None:
        """Stop ticking a standard branch whose performer is at work until the
        performer ends (:meth:`resume`), a deadline passes or the knowledge its
        over-all requirement reads changes (:meth:`knowledge_changed`)."""
        if not rt.may_rest:
            return
        reads = self._over_all_reads(rt)
        if reads is None:
            return
        self.active.discard(rt.index)
        if rt.index not in self.resting:
            self.resting.add(rt.index)
            for name in reads:
                self._readers.setdefault(name, set()).add(rt.index)

    def resume(self, index: int) -> None:
        if index in self.resting:
            self._stop_resting(index)
            self.activate(index)

    def _stop_resting(self, index: int) -> None:
        if index not in self.resting:
            return
        self.resting.discard(index)
        for name in self._reads[index] or ():
            readers = self._readers[name]
            readers.discard(index)
            if not readers:
                del self._readers[name]

    def knowledge_changed(self, change: KnowledgeChange) -> None:
        """Give a tick to the resting branches whose over-all requirement reads
        something ``change`` touched (all of them when objects came or went)."""
        if not self.resting:
            return
        if change.added_instances or change.removed_instances:
            woken = set(self.resting)
        else:
            # Plain loops over the change (a few facts), not over the branches.
            readers = self._readers
            woken = set()
            for facts in (change.added_facts, change.removed_facts):
                for atom in facts:
                    found = readers.get(atom.predicate)
                    if found:
                        woken.update(found)
            for keys in (change.changed_fluents, change.removed_fluents):
                for key in keys:
                    found = readers.get(key[0])
                    if found:
                        woken.update(found)
        for index in woken:
            self.resume(index)

    def _over_all_reads(self, rt: ActionRuntime) -> frozenset[str] | None:
        """Names the action's over-all requirement reads; None when that cannot be
        told from the condition (a derived predicate)."""
        index = rt.index
        if index not in self._reads:
            # A plan repeats its ground actions: the names are worked out once per
            # condition object (kept alive by the entry, so its id is not reused).
            cond = rt.ground.over_all
            known = self._reads_of.get(id(cond))
            if known is None or known[0] is not cond:
                if self._derived is None:
                    self._derived = frozenset(d.head.name for d in self.evaluator.domain.derived)
                walker = _Reads(self._derived)
                walker.walk(cond)
                known = (cond, None if walker.derived else frozenset(walker.names))
                self._reads_of[id(cond)] = known
            self._reads[index] = known[1]
        return self._reads[index]

    def _moved(self, rt: ActionRuntime) -> None:
        # activate(), inlined: an action has a few dependents and moves three times
        actions, active = self.actions, self.active
        for i in self.dependents[rt.index]:
            if not actions[i].finished:
                active.add(i)

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
        rt.record.start = self.now()
        rt.record.status = ActionStatus.EXECUTING
        self.progress = self.changed = True
        self._moved(rt)
        self.publish_info(rt)

    def action_ended(self, rt: ActionRuntime) -> None:
        rt.end_reached = True
        if rt.record.end is None:
            rt.record.end = self.now()
        self.progress = self.changed = True
        self._moved(rt)

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
        self.active.discard(rt.index)
        self._stop_resting(rt.index)
        self._moved(rt)
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
        self.failures.append(f"{rt.text}: {rec.message}")
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
