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

from collections.abc import Callable, Iterator, Sequence

from py_trees.behaviour import Behaviour
from py_trees.common import Status

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution import phases, waits
from plansys_bridge.execution.phases import ExecutePhase
from plansys_bridge.execution.plan_context import ActionRuntime, PlanContext
from plansys_bridge.planning.orderings import END, START, Point

__all__ = ["StandardAction"]

_BEFORE_RUN = 3
"""Phases before the run: predecessors (start), at-start requirement, at-start effects."""


_END_WAIT = 4
"""The step that waits for the predecessors of the action's end."""
_PREDECESSORS = phases.PredecessorsPhase.label
_AT_START_REQ = phases.AtStartReqPhase.label
_OVER_ALL = phases.OverAllReqPhase.label
_STATELESS: dict[int, tuple[str, Callable[[PlanContext, ActionRuntime], Status]]] = {
    2: (phases.AtStartEffectPhase.label, phases.apply_at_start_effect),
    5: (phases.AtEndReqPhase.label, phases.check_at_end_req),
    6: (phases.AtEndEffectPhase.label, phases.apply_at_end_effect),
}
"""The steps that keep no state, by index: their label (for an error) and step."""
_LAST = 6


class StandardAction(Behaviour):
    """One action of the plan, from waiting for its predecessors to its at-end
    effects (see module docs)."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        super().__init__(f"{rt.text}:{rt.index}")
        self.ctx = ctx
        self.rt = rt
        self._step = 0
        """Index of the current phase; ``_BEFORE_RUN`` is the run."""
        self._entered = False
        """Whether the current waiting step was entered (its state set up)."""
        self._waits: Sequence[tuple[int, Point]] = ()
        self._next = 0
        """The predecessor wait's state: its waits and how far it got."""
        self._deadline: float | None = None
        self._timeout: float | None = None
        """The at-start wait's state."""
        self._guarded = False
        """Whether the guards of the run are set up (``_overrun`` then is one)."""
        self._overrun: phases.OverrunPhase | None = None
        self._execution: ExecutePhase | None = None

    def tick(self) -> Iterator[Behaviour]:
        """py_trees' ``Behaviour.tick`` (see :meth:`tick_step`), as the generator
        py_trees expects."""
        self.tick_step()
        yield self

    def tick_step(self) -> None:
        """One tick without a generator, which is how :class:`PlanRoot
        <plansys_bridge.execution.tree_builder.PlanRoot>` ticks its standard branches:
        the calls of py_trees' ``Behaviour.tick`` whose effect is not nil here
        (``initialise`` and, on SUCCESS, ``terminate`` do nothing; py_trees' debug
        message is skipped), so thousands of ticks do not pay for them."""
        status = self._advance()
        if status == Status.RUNNING:
            self.status = Status.RUNNING
            return
        self.ctx.action_finished(self.rt, status == Status.SUCCESS)
        self.status = Status.SUCCESS

    def update(self) -> Status:
        status = self._advance()
        if status == Status.RUNNING:
            return Status.RUNNING
        self.ctx.action_finished(self.rt, status == Status.SUCCESS)
        return Status.SUCCESS

    def _advance(self) -> Status:
        """Step through the phases until one is RUNNING or fails. The waiting steps
        keep their state in this object's fields (:mod:`plansys_bridge.execution.waits`),
        the others keep none: every step is a plain function call, no phase object
        is made before the run, and ``Phase.run``'s error handling is inline."""
        ctx, rt = self.ctx, self.rt
        while True:
            step = self._step
            if step == _BEFORE_RUN:
                status = self._run()
            elif step in _STATELESS:
                label, function = _STATELESS[step]
                try:
                    status = function(ctx, rt)
                except PlansysBridgeError as exc:
                    rt.reason = f"{label}: {exc}"
                    status = Status.FAILURE
            elif step > _LAST:
                return Status.SUCCESS  # every phase is over
            else:
                # the waiting steps: predecessors of the start (0) or the end
                # (_END_WAIT), the at-start requirement (1)
                try:
                    if step == 1:
                        if not self._entered:
                            self._entered = True
                            self._timeout = ctx.options.at_start_timeout_for(rt.step.action)
                            self._deadline = waits.at_start_deadline(ctx, rt, self._timeout)
                        status = waits.wait_at_start_req(ctx, rt, self._deadline, self._timeout)
                    else:
                        point = START if step == 0 else END
                        if not self._entered:
                            self._entered = True
                            self._waits = ctx.graph.waits(rt.index, point)
                            self._next = 0
                        status, self._next = waits.wait_for_predecessors(
                            ctx, rt, point, self._waits, self._next
                        )
                except PlansysBridgeError as exc:
                    label = _AT_START_REQ if step == 1 else _PREDECESSORS
                    rt.reason = f"{label}: {exc}"
                    status = Status.FAILURE
            if status != Status.SUCCESS:
                return status
            self._step = step + 1
            self._entered = False

    def _run(self) -> Status:
        """The reactive part: guards first (the overrun, then the over-all
        requirement), then the execution."""
        execution = self._execution
        if execution is None and not self._guarded:
            self._guarded = True
            ctx, rt = self.ctx, self.rt
            pct = ctx.options.overrun_for(rt.step.action)
            if pct is not None and rt.step.duration > 0:
                self._overrun = phases.OverrunPhase(ctx, rt, pct)
                self._overrun.initialise()
        overrun = self._overrun
        if overrun is not None and overrun.step() != Status.SUCCESS:
            self._halt_execution()
            return Status.FAILURE
        try:
            status = phases.check_over_all_req(self.ctx, self.rt)
        except PlansysBridgeError as exc:
            self.rt.reason = f"{_OVER_ALL}: {exc}"
            status = Status.FAILURE
        if status != Status.SUCCESS:
            self._halt_execution()
            return status
        if execution is None:
            execution = self._execution = ExecutePhase(self.ctx, self.rt)
            execution.initialise()
        try:
            status = execution.step()
        except PlansysBridgeError as exc:
            status = execution.fail(f"{execution.label}: {exc}")
        if status != Status.RUNNING:
            self._execution = None
            self._overrun = None
            self._guarded = False
        return status

    def _halt_execution(self) -> None:
        if self._execution is not None:
            self._execution.halt()
            self._execution = None

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:  # settled first, as ActionBranch does
            self.ctx.action_halted(self.rt)
            self._halt_execution()
