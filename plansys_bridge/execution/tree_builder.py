"""Compile a plan graph into one py_trees behaviour tree.

The root is a :class:`PlanRoot`, a parallel composite (success when every branch
is done) with one branch per action; the graph's orderings live in each branch's
wait for its predecessors, so actions run exactly as concurrently as their
dependencies allow (no hand-made nesting of sequences, which is where PlanSys2
#155/#184/#331 went wrong). Unlike py_trees' ``Parallel`` it ticks only branches
that can move: a standard branch parked in ``WaitForPredecessors`` is ticked again
only when the happening it waits for takes place (or its action stops), a template's
when one of its predecessors starts, ends or stops, and a standard branch whose performer
is at work only when the performer ends, a deadline passes or the knowledge its
over-all requirement reads changes, so a tick costs what happened, not the size of
the plan.

Users may replace an action's subtree with a *template*: a callable that receives
an :class:`ActionNodes` (a factory of the standard behaviours for that action) and
returns the subtree. ``nodes.default()`` builds the standard one, so a template can
wrap or extend it. An action without a template is a single
:class:`~plansys_bridge.execution.standard_action.StandardAction`, which behaves as
the standard subtree does at a fraction of py_trees' cost per behaviour.
A template must keep the behaviours that other actions wait on:
``WaitForPredecessors(start)``, ``ApplyAtStartEffect`` and ``ApplyAtEndEffect``.
"""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
from py_trees.common import Status

from plansys_bridge.errors import ExecutionError
from plansys_bridge.execution.behaviours import (
    ActionBranch,
    ApplyAtEndEffect,
    ApplyAtStartEffect,
    CheckAtEndReq,
    CheckOverAllReq,
    CheckTimeout,
    ExecuteAction,
    WaitAtStartReq,
    WaitForPredecessors,
)
from plansys_bridge.execution.plan_context import ActionRuntime, PlanContext
from plansys_bridge.execution.standard_action import StandardAction
from plansys_bridge.knowledge.evaluation import GroundAction
from plansys_bridge.planning.orderings import END, START

__all__ = ["ActionNodes", "PlanRoot", "TemplateError", "build_tree", "default_template"]


class TemplateError(ExecutionError):
    """A user template returned a subtree the executor cannot run safely."""


class ActionNodes:
    """The standard behaviours of one action, for templates to assemble.

    Attributes a template may read: ``action`` (name), ``arguments``, ``text``
    (``(move r1 a b)``), ``index`` (plan step), ``duration`` (planned),
    ``ground`` (the ground action: conditions and effects), ``context``.

    The tree is ticked only when something happens, so a custom behaviour that
    must be looked at again later asks for it: ``context.schedule(mission_time)``
    (a timer) or ``context.wake()`` (as soon as possible, from the loop's thread).
    """

    def __init__(self, ctx: PlanContext, rt: ActionRuntime) -> None:
        self.context = ctx
        self.runtime = rt
        self.action = rt.step.action
        self.arguments = rt.step.arguments
        self.text = rt.text
        self.index = rt.index
        self.duration = rt.step.duration
        self.ground: GroundAction = rt.ground

    def wait_for_predecessors(self) -> WaitForPredecessors:
        return WaitForPredecessors(self.context, self.runtime, START)

    def wait_for_end_predecessors(self) -> WaitForPredecessors:
        return WaitForPredecessors(self.context, self.runtime, END)

    def wait_at_start_req(self, timeout: float | str | None = "default") -> WaitAtStartReq:
        options = self.context.options
        t = options.at_start_timeout_for(self.action) if timeout == "default" else timeout
        assert not isinstance(t, str)
        return WaitAtStartReq(self.context, self.runtime, t)

    def apply_at_start_effect(self) -> ApplyAtStartEffect:
        return ApplyAtStartEffect(self.context, self.runtime)

    def check_over_all_req(self) -> CheckOverAllReq:
        return CheckOverAllReq(self.context, self.runtime)

    def execute_action(self) -> ExecuteAction:
        return ExecuteAction(self.context, self.runtime)

    def check_timeout(self, overrun_percentage: float) -> CheckTimeout:
        return CheckTimeout(self.context, self.runtime, overrun_percentage)

    def check_at_end_req(self) -> CheckAtEndReq:
        return CheckAtEndReq(self.context, self.runtime)

    def apply_at_end_effect(self) -> ApplyAtEndEffect:
        return ApplyAtEndEffect(self.context, self.runtime)

    def running(self, *extra: py_trees.behaviour.Behaviour) -> py_trees.composites.Sequence:
        """ReactiveSequence[CheckTimeout?, CheckOverAllReq, *extra, ExecuteAction]:
        every guard is re-checked on each tick while the action runs."""
        guards: list[py_trees.behaviour.Behaviour] = []
        pct = self.context.options.overrun_for(self.action)
        if pct is not None and self.duration > 0:
            guards.append(self.check_timeout(pct))
        guards.append(self.check_over_all_req())
        guards.extend(extra)
        guards.append(self.execute_action())
        return py_trees.composites.Sequence(
            f"Running {self.text}:{self.index}", memory=False, children=guards
        )

    def default(self) -> py_trees.composites.Sequence:
        """The standard subtree (see :mod:`plansys_bridge.execution.behaviours`)."""
        return py_trees.composites.Sequence(
            f"{self.text}:{self.index}",
            memory=True,
            children=[
                self.wait_for_predecessors(),
                self.wait_at_start_req(),
                self.apply_at_start_effect(),
                self.running(),
                self.wait_for_end_predecessors(),
                self.check_at_end_req(),
                self.apply_at_end_effect(),
            ],
        )


def default_template(nodes: ActionNodes) -> py_trees.behaviour.Behaviour:
    """The standard per-action subtree."""
    return nodes.default()


_DONE = (Status.SUCCESS, Status.FAILURE)


class PlanRoot(py_trees.composites.Composite):
    """Parallel root over the action branches; ticks only the active ones (see module
    docs) and succeeds once every branch is done (a branch records its own failure)."""

    def __init__(
        self, name: str, ctx: PlanContext, children: list[py_trees.behaviour.Behaviour]
    ) -> None:
        super().__init__(name)
        # Composite.add_child's work, without its call per branch and without asking
        # each branch for its id (a standard action makes its uuid on first use)
        for child in children:
            if child.parent is not None:
                raise RuntimeError(
                    f"behaviour '{child.name}' already has parent '{child.parent.name}'"
                )
            child.parent = self
        self.children = children
        self.ctx = ctx

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """py_trees' generator tick: yields each branch ticked, then the root."""
        self._enter()
        if self.ctx.touched:
            self._touch()
        for child in self._due():
            if type(child) is StandardAction:
                child.tick_step()
                yield child
            else:
                yield from child.tick()
        self._settle()
        yield self

    def tick_once(self) -> None:
        """The same tick as :meth:`tick` without its generators, which is how the
        executor ticks: a standard branch is stepped by a plain call, so a tick
        costs a call per branch that can move and nothing per finished or waiting
        branch."""
        if self.status != Status.RUNNING:
            self._enter()
        ctx = self.ctx
        if ctx.touched:
            self._touch()
        # _due(), written out: no comprehension's call per tick
        due = []
        actions, children = ctx.actions, self.children
        for index in sorted(ctx.active):
            child = children[index]
            if not actions[index].finished and child.status not in _DONE:
                due.append(child)
        for child in due:
            if type(child) is StandardAction:
                child.tick_step()
            else:
                for _ in child.tick():
                    pass
        if ctx.unfinished:  # _settle(), inlined: a call per tick
            self.status = Status.RUNNING
        else:
            self.stop(Status.SUCCESS)

    def _due(self) -> list[py_trees.behaviour.Behaviour]:
        """The branches a tick steps, in plan order: active (neither parked nor
        resting) and not over. Taken before the first is stepped: a branch only
        ever settles itself, so stepping one does not end another."""
        actions, children = self.ctx.actions, self.children
        return [
            children[index]
            for index in sorted(self.ctx.active)
            if not actions[index].finished and children[index].status not in _DONE
        ]

    def _touch(self) -> None:
        """The standard branches not yet ticked whose predecessors moved
        (``PlanContext.touched``) are RUNNING from now on, as the tick that found
        them waiting used to make them."""
        actions, children = self.ctx.actions, self.children
        for index in self.ctx.touched:
            child = children[index]
            if child.status == Status.INVALID and not actions[index].finished:
                child.status = Status.RUNNING
        self.ctx.touched.clear()

    def _enter(self) -> None:
        if self.status != Status.RUNNING:
            for child in self.children:
                if child.status != Status.INVALID:
                    child.stop(Status.INVALID)
            self.initialise()

    def _settle(self) -> None:
        if self.ctx.unfinished == 0:
            self.stop(Status.SUCCESS)
        else:
            self.status = Status.RUNNING


def build_tree(ctx: PlanContext) -> PlanRoot:
    """A :class:`PlanRoot` with a branch per action: a :class:`StandardAction`, or
    a template's subtree wrapped in an :class:`ActionBranch`."""
    branches: list[py_trees.behaviour.Behaviour] = []
    options = ctx.options
    # options.template_for(), as a look-up: once per action
    template_for, default = options.templates.get, options.action_template
    for rt in ctx.actions:
        template = template_for(rt.step.action, default)
        rt.may_rest = template is None
        if template is None:
            branches.append(StandardAction(ctx, rt))
            continue
        subtree = template(ActionNodes(ctx, rt))
        _check_template(subtree, rt)
        branches.append(ActionBranch(ctx, rt, subtree))
    ctx.park_waiting()
    return PlanRoot(f"plan {ctx.plan_id}/{ctx.plan_index}", ctx, branches)


def _check_template(subtree: object, rt: ActionRuntime) -> None:
    if not isinstance(subtree, py_trees.behaviour.Behaviour):
        raise TemplateError(
            f"template for action {rt.step.action!r} returned {type(subtree).__name__}, "
            "expected a py_trees behaviour"
        )
    found = list(subtree.iterate())
    missing = []
    if not any(isinstance(b, WaitForPredecessors) and b.point == START for b in found):
        missing.append("WaitForPredecessors(start)")
    if not any(isinstance(b, ApplyAtStartEffect) for b in found):
        missing.append("ApplyAtStartEffect")
    if not any(isinstance(b, ApplyAtEndEffect) for b in found):
        missing.append("ApplyAtEndEffect")
    if missing:
        raise TemplateError(
            f"template for action {rt.step.action!r} ({rt.text}) lacks {', '.join(missing)}; "
            "other actions wait on them"
        )
