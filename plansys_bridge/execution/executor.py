"""The executor: run plans as behaviour trees, replan on failure, report everything.

Typical use (a mission runner, the terminal, an experiment)::

    executor = Executor(hub, domain, knowledge, planner, ExecutorOptions(max_replans=3))
    result = await executor.execute(plan, goal=knowledge.get_goal())
    print(result.status, result.replans, f"{result.efficiency_percent:.1f} %")

What happens in :meth:`Executor.execute`:

1. The plan's dependency graph is built on the current knowledge
   (:func:`build_plan_graph`) and checked: a requirement nothing explains rejects
   the plan (``status="rejected"``, ``message`` names action and requirement).
2. The graph is compiled into a py_trees tree (:func:`build_tree`) and ticked
   *when something happens*: an action's performer finishes or fails (its client
   task completes), the knowledge changes (``ProblemExpert.subscribe``), or a
   deadline a behaviour registered is due (at-start timeout, duration overrun).
   The tree is ticked again at once while anything moves, so a successor's
   ``ExecuteAction`` starts in the same loop turn its predecessor's FINISH is
   processed; there is no fixed 10 Hz polling.
3. On a failure (an action fails, an at-start requirement times out, an over-all
   requirement breaks and halts its action), no further action starts; actions
   already running and unaffected finish, so their effects are applied whole
   (with ``ExecutorOptions.halt_on_failure`` they are halted instead).
   An action halted after its at-start effects has those effects undone (see
   ``ExecutorOptions.rollback_on_halt``). Then the planner is asked for a new plan
   from the current knowledge (``knowledge.to_problem()`` with the goal) in a
   worker thread, and execution continues with it, ``max_replans`` times at most.

Several plans may execute at once (each ``execute`` call has its own tree and
``plan_id``; request ids ``<plan_id>/<plan number>/<step>`` keep their auctions
apart). ``cancel(plan_id)`` halts one, ``cancel()`` all. Published on the hub:
``executing_plan`` (each plan as it starts), ``action_execution_info`` (every
status change and feedback), ``dot_graph`` (the coloured graph after changes).
"""

from __future__ import annotations

import asyncio
import dataclasses
import itertools
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING

import py_trees
from py_trees.common import Status

from plansys_bridge.errors import ExecutionError, PlansysBridgeError
from plansys_bridge.execution.behaviours import PlanContext
from plansys_bridge.execution.dot import IncrementalDot
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.execution.tree_builder import build_tree
from plansys_bridge.hub.auction import ClientPhase
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecutionInfo, DotGraph, ExecutingPlan, Topics
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.pddl.model import Atom, Condition, Domain
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.plan_graph import PlanGraph, build_plan_graph

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.planning.planner import Planner

__all__ = ["Executor"]

log = logging.getLogger(__name__)

_plan_ids = itertools.count(1)


class _Execution:
    """Book-keeping of one ``execute`` call (one plan_id)."""

    def __init__(self, plan_id: str) -> None:
        self.plan_id = plan_id
        self.cancelled = False
        self.context: PlanContext | None = None

    def cancel(self) -> None:
        self.cancelled = True
        if self.context is not None:
            self.context.wake()


class Executor:
    """Executes plans on a hub against a live knowledge base (see module docs).

    ``planner`` may be None: a failure then ends the execution (no replanning).
    """

    def __init__(
        self,
        hub: Hub,
        domain: Domain,
        knowledge: ProblemExpert,
        planner: Planner | None = None,
        options: ExecutorOptions | None = None,
    ) -> None:
        self.hub = hub
        self.domain = domain
        self.knowledge = knowledge
        self.planner = planner
        self.options = options if options is not None else ExecutorOptions()
        existing = getattr(knowledge, "evaluator", None)
        self.evaluator: Evaluator = (
            existing
            if isinstance(existing, Evaluator) and existing.domain == domain
            else Evaluator(domain)
        )
        self._executions: dict[str, _Execution] = {}

    # ------------------------------------------------------------ public API

    @property
    def running(self) -> list[str]:
        """plan_ids of the executions under way."""
        return list(self._executions)

    def build_graph(self, plan: Plan) -> PlanGraph:
        """The plan's dependency graph on the current knowledge (not checked)."""
        return build_plan_graph(plan, self.domain, self.knowledge.state(), evaluator=self.evaluator)

    def cancel(self, plan_id: str | None = None) -> None:
        """Halt one execution (``plan_id``) or all of them; running actions get a
        CANCEL, and ``execute`` returns with ``status="cancelled"``."""
        if plan_id is None:
            for execution in self._executions.values():
                execution.cancel()
            return
        found = self._executions.get(plan_id)
        if found is None:
            running = ", ".join(self._executions) or "none"
            raise ExecutionError(f"no plan {plan_id!r} is executing (running: {running})")
        found.cancel()

    async def execute(
        self,
        plan: Plan,
        *,
        goal: Condition | None = None,
        plan_id: str | None = None,
        on_info: Callable[[ActionExecutionInfo], None] | None = None,
    ) -> ExecutionResult:
        """Execute ``plan`` until it succeeds, fails beyond the replanning budget, or
        is cancelled.

        ``goal``: what replanning aims at (default: the knowledge's goal); when given,
        a plan that ends without achieving it counts as failed. ``on_info`` is called
        with every ``ActionExecutionInfo`` published.
        """
        pid = plan_id if plan_id is not None else f"plan-{next(_plan_ids)}"
        if pid in self._executions:
            raise ExecutionError(f"a plan with plan_id {pid!r} is already executing")
        execution = _Execution(pid)
        self._executions[pid] = execution
        clock = self.hub.clock
        result = ExecutionResult(success=False, status="failed", plan_id=pid, started=clock.now())
        try:
            await self._execute(plan, goal, execution, on_info, result)
        finally:
            result.finished = clock.now()
            del self._executions[pid]
        return result

    # ------------------------------------------------------------ the replanning loop

    async def _execute(
        self,
        plan: Plan,
        goal: Condition | None,
        execution: _Execution,
        on_info: Callable[[ActionExecutionInfo], None] | None,
        result: ExecutionResult,
    ) -> None:
        current: Plan | None = plan
        while current is not None:
            result.plans.append(current)
            try:
                graph = self.build_graph(current)
                graph.check()
            except ExecutionError as exc:  # PlanGraphError, or an unknown action
                result.status, result.message = "rejected", str(exc)
                return
            ctx = PlanContext(
                hub=self.hub,
                knowledge=self.knowledge,
                evaluator=self.evaluator,
                graph=graph,
                options=self.options,
                plan_id=execution.plan_id,
                plan_index=len(result.plans) - 1,
                on_info=on_info,
            )
            execution.context = ctx
            if self.hub.has_audience(Topics.EXECUTING_PLAN):
                self.hub.publish(
                    Topics.EXECUTING_PLAN, ExecutingPlan(current.to_msg(), execution.plan_id)
                )
            await self._run(ctx, execution, goal)
            result.actions.extend([rt.record for rt in ctx.actions])
            if ctx.cancelled:
                result.status, result.message = "cancelled", "cancelled"
                return
            failed = bool(ctx.failures)
            reason = "; ".join(ctx.failures)
            if not failed and goal is not None and not self._goal_holds(goal):
                failed, reason = True, "the plan ended without achieving the goal"
            if not failed:
                result.success, result.status, result.message = True, "succeeded", ""
                return
            result.message = reason
            current = await self._replan(goal, result, execution)

    def _goal_holds(self, goal: Condition) -> bool:
        return self.evaluator.holds(goal, self.knowledge.state())

    async def _replan(
        self, goal: Condition | None, result: ExecutionResult, execution: _Execution
    ) -> Plan | None:
        target = goal if goal is not None else self.knowledge.get_goal()
        if target is not None and self._goal_holds(target):
            result.success, result.status = True, "succeeded"
            result.message += " (the goal holds anyway)"
            return None
        if self.planner is None or target is None or result.replans >= self.options.max_replans:
            why = (
                "no planner to replan with"
                if self.planner is None
                else "no goal to replan for"
                if target is None
                else f"replanning budget of {self.options.max_replans} used up"
            )
            result.status = "failed"
            result.message += f" ({why})"
            return None
        problem = dataclasses.replace(self.knowledge.to_problem(), goal=target)
        planner = self.planner
        try:
            found = await asyncio.to_thread(planner.solve, self.domain, problem)
        except PlansysBridgeError as exc:
            result.status, result.message = (
                "replan_failed",
                f"{result.message}; replanning failed: {exc}",
            )
            return None
        if execution.cancelled:
            result.status, result.message = "cancelled", "cancelled while replanning"
            return None
        if found.plan is None or not found.solved:
            result.status = "replan_failed"
            result.message += f"; replanning failed: {found.status.value} {found.message}".rstrip()
            return None
        result.replans += 1
        log.info("plan %s: replan %d after %s", execution.plan_id, result.replans, result.message)
        return found.plan

    # ------------------------------------------------------------ event-driven ticking

    async def _run(self, ctx: PlanContext, execution: _Execution, goal: Condition | None) -> None:
        loop = asyncio.get_running_loop()
        root = build_tree(ctx)
        event = asyncio.Event()
        # the context wakes the loop itself, and is the knowledge's subscriber itself
        # (it hands a change made in another thread over to the loop): no function
        # in between that only forwards, twice per action
        ctx.bind_wake(event.set, loop)
        unsubscribe = self.knowledge.subscribe(ctx.knowledge_changed)
        clock = self.hub.clock
        name = f"{ctx.plan_id}/{ctx.plan_index}"
        # the DOT text is made when somebody first listens (see _publish_dot), of the
        # goal's atoms as they are now
        dot = _LazyDot(ctx, self._goal_atoms(goal), name) if self.options.publish_dot else None
        timer: asyncio.TimerHandle | None = None
        armed_for: float | None = None
        dot_due: float | None = None  # the DOT's deadline last scheduled
        try:
            last_dot = clock.now()
            if dot is not None:
                self._publish_dot(ctx, dot)
            while True:
                event.clear()
                if execution.cancelled and not ctx.cancelled:
                    ctx.cancelled = True
                    root.stop(Status.INVALID)
                    break
                ctx.pass_deadlines()
                self._tick(root, ctx)
                if ctx.changed and dot is not None:
                    due = last_dot + self.options.dot_period
                    if clock.now() >= due:
                        self._publish_dot(ctx, dot)
                        last_dot = clock.now()
                    elif due != dot_due:  # not once more per wake-up until it comes
                        ctx.schedule(due)
                        dot_due = due
                if root.status != Status.RUNNING:
                    break
                deadline = ctx.next_deadline()
                if deadline != armed_for or (timer is not None and timer.when() <= loop.time()):
                    # The timer of the last wait serves this one when the earliest
                    # deadline is still the same (most wake-ups are a performer's
                    # message, not a deadline): no new timer and no cancel per wait.
                    if timer is not None:
                        timer.cancel()
                        timer = None
                    armed_for = deadline
                    if deadline is not None:
                        delay = max(0.0, (deadline - clock.now()) * clock.time_scale)
                        timer = loop.call_later(delay, event.set)
                await event.wait()
        except BaseException:
            # cancelled from outside, or a template's behaviour raised: stop every
            # performer of this plan before letting the exception through
            ctx.cancelled = True
            root.stop(Status.INVALID)
            for task in list(ctx.tasks):
                task.cancel()
            raise
        finally:
            if timer is not None:
                timer.cancel()
            unsubscribe()
            ctx.bind_wake(lambda: None)
            if dot is not None and ctx.changed:
                self._publish_dot(ctx, dot)
        # every auction client ends before the plan does (a cancel completes quickly)
        done = ClientPhase.DONE
        for rt in ctx.actions:
            client = rt.client
            if client is not None and client.phase is not done:  # cancel() would return
                client.cancel()
        if ctx.tasks:
            await asyncio.gather(*list(ctx.tasks), return_exceptions=True)

    def _tick(self, root: py_trees.behaviour.Behaviour, ctx: PlanContext) -> None:
        for _ in range(self.options.max_ticks_per_wake):
            if root.status == Status.RUNNING and ctx.unfinished and not (ctx.active or ctx.touched):
                # a round would tick no branch and leave the root as it is: the round
                # after the last move, and the wake-up an effect applied in the last
                # tick asked for, come to nothing about every other wake-up
                return
            ctx.progress = False
            root.tick_once()
            if ctx.halt_requested:
                self._halt_running(root, ctx)
            if root.status != Status.RUNNING or not ctx.progress:
                return

    def _halt_running(self, root: py_trees.behaviour.Behaviour, ctx: PlanContext) -> None:
        """Stop every branch still under way (their performers get a CANCEL)."""
        ctx.halt_requested = False
        branches = list(root.children) if isinstance(root, py_trees.composites.Composite) else []
        for rt, branch in zip(ctx.actions, branches, strict=False):
            if not rt.finished and branch.status == Status.RUNNING:
                rt.reason = "halted: the plan stopped after " + ctx.failures[0]
                branch.stop(Status.INVALID)
        ctx.progress = True

    def _goal_atoms(self, goal: Condition | None) -> list[Atom]:
        target = goal if goal is not None else self.knowledge.get_goal()
        if target is None:
            return []
        positive, _negative = self.evaluator.condition_atoms(target, {}, self.knowledge.state())
        return sorted(positive, key=str)

    def _publish_dot(self, ctx: PlanContext, dot: _LazyDot) -> None:
        ctx.changed = False
        changed = ctx.take_changed_steps()
        if not self.hub.has_audience(Topics.DOT_GRAPH):
            return  # nobody to show it to (yet): the steps' states are read when made
        made = dot.made
        if made is None:
            made = dot.make()
        else:
            for index in changed:
                made.set_status(index, ctx.actions[index].record.status)
        self.hub.publish(Topics.DOT_GRAPH, DotGraph(made.text(), ctx.plan_id))


class _LazyDot:
    """The plan's :class:`IncrementalDot`, made on its first publication with an
    audience: its labels, edges and sub-goals are written for every action of the
    plan at once, work wasted on a graph nobody watches."""

    def __init__(self, ctx: PlanContext, goal_atoms: list[Atom], name: str) -> None:
        self.ctx = ctx
        self.goal_atoms = goal_atoms
        self.name = name
        self.made: IncrementalDot | None = None

    def make(self) -> IncrementalDot:
        """The graph, each step in its state now (as publications since the start
        would have left it)."""
        made = self.made = IncrementalDot(self.ctx.graph, self.goal_atoms, name=self.name)
        for index, rt in enumerate(self.ctx.actions):
            made.set_status(index, rt.record.status)
        return made
