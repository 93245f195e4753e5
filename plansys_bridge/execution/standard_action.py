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

from collections.abc import Callable, Iterator

from py_trees.behaviour import Behaviour
from py_trees.common import Status

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution import phases
from plansys_bridge.execution.phases import ExecutePhase, Phase
from plansys_bridge.execution.plan_context import ActionRuntime, PlanContext
from plansys_bridge.planning.orderings import END, START

__all__ = ["StandardAction"]

_BEFORE_RUN = 3
"""Phases before the run: predecessors (start), at-start requirement, at-start effects."""


_END_WAIT = 4
"""The step that waits for the predecessors of the action's end."""
_OVER_ALL = phases.OverAllReqPhase.label
_STATELESS: dict[int, tuple[str, Callable[[PlanContext, ActionRuntime], Status]]] = {
    2: (phases.AtStartEffectPhase.label, phases.apply_at_start_effect),
    5: (phases.AtEndReqPhase.label, phases.check_at_end_req),
    6: (phases.AtEndEffectPhase.label, phases.apply_at_end_effect),
}
"""The steps that keep no state, by index: their label (for an error) and step."""


class StandardAction(Behaviour):
    """One action of the plan, from waiting for its predecessors to its at-end
    effects (see module docs)."""

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        super().__init__(f"{rt.text}:{rt.index}")
        self.ctx = ctx
        self.rt = rt
        self._step = 0
        """Index of the current phase; ``_BEFORE_RUN`` is the run."""
        self._phase: Phase | None = None
        self._guarded = False
        """Whether the guards of the run are set up (``_overrun`` then is one)."""
        self._overrun: phases.OverrunPhase | None = None
        self._execution: ExecutePhase | None = None

    def _make(self, step: int) -> Phase | None:
        """The phase object of a step that keeps state (see ``_STATELESS``)."""
        ctx, rt = self.ctx, self.rt
        if step == 0:
            return phases.PredecessorsPhase(ctx, rt, START)
        if step == 1:
            return phases.AtStartReqPhase(ctx, rt, ctx.options.at_start_timeout_for(rt.step.action))
        if step == _END_WAIT:
            return phases.PredecessorsPhase(ctx, rt, END)
        return None

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
        """Step through the phases until one is RUNNING or fails. A step that keeps
        no state is a plain function call (no phase object); a phase is stepped
        directly (``Phase.step``, with ``Phase.run``'s error handling inline) and
        entered only when it has something to do on entry."""
        while True:
            step = self._step
            if step == _BEFORE_RUN:
                status = self._run()
            elif step in _STATELESS:
                label, function = _STATELESS[step]
                try:
                    status = function(self.ctx, self.rt)
                except PlansysBridgeError as exc:
                    self.rt.reason = f"{label}: {exc}"
                    status = Status.FAILURE
            else:
                phase = self._phase
                if phase is None:
                    if step == _END_WAIT and not self.ctx.graph.waits(self.rt.index, END):
                        self._step = step + 1  # nothing to wait for: the phase would succeed
                        continue
                    phase = self._phase = self._make(step)
                    if phase is None:
                        return Status.SUCCESS
                    if phase.enters:
                        phase.initialise()
                try:
                    status = phase.step()
                except PlansysBridgeError as exc:
                    status = phase.fail(f"{phase.label}: {exc}")
            if status != Status.SUCCESS:
                return status
            self._step = step + 1
            self._phase = None

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
