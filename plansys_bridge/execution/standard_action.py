"""The standard action as one py_trees behaviour.

Without a template, an action needs no subtree of its own: a single
:class:`StandardAction` goes through the same phases, in the same order, with the
same tick semantics as :meth:`ActionNodes.default
<plansys_bridge.execution.tree_builder.ActionNodes.default>` wrapped in an
:class:`~plansys_bridge.execution.behaviours.ActionBranch`:

* the phases before and after the run behave as a sequence with memory: each is
  entered once (``initialise``), ticked until it is no longer RUNNING, and a
  success moves on to the next phase within the same tick;
* while the action runs, the overrun and over-all guards are re-checked on each
  tick before the execution is looked at (a reactive sequence), and a failing
  guard halts the execution (its performer gets a CANCEL);
* when the phases end, the action is settled (``action_finished``), and a stop from
  outside halts the execution and settles it as halted (``action_halted``).

What it saves is py_trees' fixed cost: one behaviour (one uuid, one logger, one
tick generator) per action instead of eleven, and one visit per tick instead of
a walk through the decorator and two sequences.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import BlackBoxLevel, Status

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution import phases, waits
from plansys_bridge.execution.effect_delta import EffectDelta
from plansys_bridge.execution.phases import ExecutePhase
from plansys_bridge.execution.plan_context import ActionRuntime, PlanContext
from plansys_bridge.planning.orderings import END, GROUND, START

__all__ = ["StandardAction"]

_RUNNING = Status.RUNNING
_SUCCESS = Status.SUCCESS
_FAILURE = Status.FAILURE

_RUN = 3
"""The step that runs the action: phases before it are the wait for the
predecessors of the start (0), the at-start requirement (1) and effects (2)."""
_END_WAIT = 4
"""The step that waits for the predecessors of the action's end."""
_LAST = 6
"""The at-end effects; after them (5: the at-end requirement) the action is over."""
_LABELS = {
    0: phases.PredecessorsPhase.label,
    1: phases.AtStartReqPhase.label,
    2: phases.AtStartEffectPhase.label,
    _END_WAIT: phases.PredecessorsPhase.label,
    5: phases.AtEndReqPhase.label,
    _LAST: phases.AtEndEffectPhase.label,
}
"""The label an error of each step (but the run) is reported with."""
_OVER_ALL = phases.OverAllReqPhase.label


class StandardAction(Behaviour):
    """One action of the plan, from waiting for its predecessors to its at-end
    effects (see module docs)."""

    # Behaviour.__init__'s attributes whose value starts the same for every action,
    # and this behaviour's own state, read from the class until first set: a plan of
    # thousands of actions makes each with two attribute writes
    status = Status.INVALID
    parent = None
    feedback_message = ""
    blackbox_level = BlackBoxLevel.NOT_A_BLACKBOX
    _step = 0
    """Index of the current phase; ``_RUN`` is the run."""
    _entered = False
    """Whether the at-start wait was entered (its deadline set up)."""
    _next = 0
    """How far through its predecessors the current wait got."""
    _deadline: float | None = None
    _timeout: float | None = None
    """The at-start wait's state."""
    _guarded = False
    """Whether the guards of the run are set up (``_overrun`` then is one)."""
    _overrun: phases.OverrunPhase | None = None
    _execution: ExecutePhase | None = None

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        # Behaviour.__init__'s other attributes (name, qualified name, lists of
        # children and blackboards), its uuid4 (from os.urandom), logger and tick
        # generator are made on first use (__getattr__): a plan of thousands of
        # actions asks for none of them unless it is stopped early or shown.
        self.ctx = ctx
        self.rt = rt

    def __getattr__(self, name: str) -> Any:
        """What ``Behaviour.__init__`` makes, when first asked for (the uuid is a
        fresh uuid4, the lists new ones)."""
        value: Any
        if name == "name":
            value = f"{self.rt.step.text}:{self.rt.index}"
        elif name == "qualified_name":
            value = f"{type(self).__qualname__}/{self.name}"
        elif name == "children" or name == "blackboards":
            value = []
        elif name == "id":
            value = uuid.uuid4()
        elif name == "logger":
            value = py_trees.logging.Logger(self.name)
        elif name == "iterator":
            value = self.tick()
        elif name == "ctx" or name == "rt":  # not yet set (copy, pickle): no recursion
            raise AttributeError(name)
        else:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        self.__dict__[name] = value
        return value

    def tick(self) -> Iterator[Behaviour]:
        """py_trees' ``Behaviour.tick`` (see :meth:`tick_step`), as the generator
        py_trees expects."""
        self.tick_step()
        yield self

    def update(self) -> Status:
        self.tick_step()
        return self.status

    def tick_step(self) -> None:
        """One tick without a generator, which is how :class:`PlanRoot
        <plansys_bridge.execution.tree_builder.PlanRoot>` ticks its standard branches:
        the calls of py_trees' ``Behaviour.tick`` whose effect is not nil here
        (``initialise`` and, on SUCCESS, ``terminate`` do nothing; py_trees' debug
        message is skipped), so thousands of ticks do not pay for them.

        It steps through the phases until one is RUNNING or fails. The waiting
        steps keep their state in this object's fields, the others keep none, and
        each step's common case is written out here: a requirement that holds is
        one look-up (the phase's function, which words what is missing, is called
        when it does not), an effect is applied without a phase function, and no
        phase object is made before the run."""
        ctx, rt = self.ctx, self.rt
        step = self._step
        while True:
            if step == _RUN:
                # The reactive part: the guards first (the overrun, then the over-all
                # requirement), then the execution; a failing guard halts it.
                execution = self._execution
                if execution is None and not self._guarded:
                    self._guarded = True
                    if ctx.options.overrun_percentage is not None or ctx.options.action_timeouts:
                        self._guard(ctx, rt)
                overrun = self._overrun
                if overrun is not None and overrun.step() is not _SUCCESS:
                    status = _FAILURE
                else:
                    try:
                        if ctx.evaluator.holds(
                            rt.ground.over_all, ctx.knowledge.state(), GROUND, rt.step.duration
                        ):
                            status = _SUCCESS
                        else:
                            status = phases.check_over_all_req(ctx, rt)
                    except PlansysBridgeError as exc:
                        rt.reason = f"{_OVER_ALL}: {exc}"
                        status = _FAILURE
                if status is not _SUCCESS:
                    self._halt_execution()
                    break
                if execution is None:
                    execution = self._execution = ExecutePhase(ctx, rt)
                    execution.initialise()
                task = execution.task
                if task is not None and not task.done():
                    ctx.rest(rt)  # ExecutePhase.step's answer while the performer works
                    status = _RUNNING
                    break
                try:
                    status = execution.step()
                except PlansysBridgeError as exc:
                    status = execution.fail(f"{execution.label}: {exc}")
                if status is not _RUNNING:
                    self._execution = None
                    self._overrun = None
                    self._guarded = False
            else:
                try:
                    if step == 0 or step == _END_WAIT:
                        # the predecessors of the start or the end: all reached (or
                        # none) needs no call, unless the plan is stopping
                        found = (ctx.start_waits if step == 0 else ctx.end_waits)[rt.index]
                        n = self._next
                        for j, point in found[n:]:  # those that took place, in order
                            other = ctx.actions[j]
                            if not (other.start_reached if point == START else other.end_reached):
                                break
                            n += 1
                        if n == len(found) and (step or not (ctx.draining or ctx.cancelled)):
                            status = _SUCCESS
                        else:
                            status, self._next = waits.wait_for_predecessors(
                                ctx, rt, START if step == 0 else END, found, self._next
                            )
                    elif step == 1:
                        if not (ctx.draining or ctx.cancelled) and ctx.evaluator.holds(
                            rt.ground.at_start, ctx.knowledge.state(), GROUND, rt.step.duration
                        ):
                            status = _SUCCESS
                        else:
                            # A wait begins: its timeout, and when it gives up. Only
                            # now: a requirement that holds at once (nearly all)
                            # waits for nothing, and a deadline registered for it
                            # anyway woke the executor for nothing when it came.
                            if not self._entered:
                                self._entered = True
                                self._enter_at_start_wait(ctx, rt)
                            status = waits.wait_at_start_req(ctx, rt, self._deadline, self._timeout)
                    elif step == 2:
                        # phases.apply_at_start_effect, written out
                        applied = ctx.knowledge.apply(
                            rt.ground.start_effect, GROUND, rt.step.duration
                        )
                        rt.start_delta = EffectDelta(
                            applied.added, applied.deleted, applied.fluents
                        )
                        ctx.action_started(rt)
                        status = _SUCCESS
                    elif step == 5:
                        if ctx.evaluator.holds(
                            rt.ground.at_end, ctx.knowledge.state(), GROUND, rt.step.duration
                        ):
                            status = _SUCCESS
                        else:
                            status = phases.check_at_end_req(ctx, rt)
                    elif step == _LAST:
                        ctx.knowledge.apply(rt.ground.end_effect, GROUND, rt.step.duration)
                        ctx.action_ended(rt)
                        status = _SUCCESS
                    else:
                        status = _SUCCESS  # every phase is over
                        break
                except PlansysBridgeError as exc:
                    rt.reason = f"{_LABELS[step]}: {exc}"
                    status = _FAILURE
            if status is not _SUCCESS:
                break
            step += 1
            self._entered = False
            self._next = 0
        self._step = step
        if status is _RUNNING:
            self.status = _RUNNING
            return
        ctx.action_finished(rt, status is _SUCCESS)
        self.status = _SUCCESS

    def _enter_at_start_wait(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        """The at-start wait's timeout, and the deadline it gives up at (registered
        with the context, so a tick comes then)."""
        options = ctx.options
        timeout = self._timeout = (
            options.at_start_timeout_for(rt.step.action)
            if options.action_timeouts
            else options.at_start_timeout
        )
        if timeout is not None:  # waits.at_start_deadline, written out
            self._deadline = ctx.now() + timeout
            ctx.schedule(self._deadline, rt.index)

    def _guard(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        """Set up the guards of the run: the overrun's, when the action has one."""
        options = ctx.options
        pct = (
            options.overrun_for(rt.step.action)
            if options.action_timeouts
            else options.overrun_percentage
        )
        if pct is not None and rt.step.duration > 0:
            self._overrun = phases.OverrunPhase(ctx, rt, pct)
            self._overrun.initialise()

    def _halt_execution(self) -> None:
        if self._execution is not None:
            self._execution.halt()
            self._execution = None

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:  # settled first, as ActionBranch does
            self.ctx.action_halted(self.rt)
            self._halt_execution()
