"""A parked branch is woken by the one happening it waits for, and the plan runs as
when every move of a predecessor woke it.

Standard branches parked in their wait for predecessors are woken only when what
they wait for takes place (``PlanContext.park_on``), and branches never ticked are
given the RUNNING status a tick that found them waiting gave (``touched``). The
general path, kept here as the reference, wakes every dependent of an action on
each of its moves, as template branches still are; both must give the same records,
hub messages (with their mission times), DOT and knowledge, whatever happens when.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest
from execution_helpers import Event, PerformerSpec
from hypothesis import example, given, settings
from hypothesis import strategies as st
from test_standard_action import PARALLEL, PERFORMERS, PLAN, _context, _knowledge, observe

from plansys_bridge.execution.action_runtime import ActionRuntime
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.plan_context import PlanContext
from plansys_bridge.execution.tree_builder import build_tree, default_template
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.planning.orderings import END, START, Point

CROSS = (
    "0: (patrol r2d2 kitchen) [2]\n"
    "0: (move c3po hall kitchen) [5]\n"
    "2.001: (move r2d2 kitchen hall) [5]\n"
    "5.001: (patrol c3po kitchen) [2]\n"
    "7.002: (patrol r2d2 hall) [2]\n"
)
PLANS = {"chain": PLAN, "parallel": PARALLEL, "cross": CROSS}
EVENTS: dict[str, Callable[[ProblemExpert, Executor], None] | None] = {
    "none": None,
    "cancel": lambda _k, executor: executor.cancel(),
    "battery": lambda k, _e: k.remove_predicate("(battery_full r2d2)"),
    "corridor": lambda k, _e: k.remove_predicate("(connected kitchen hall)"),
}
SLOW_C3PO = [*PERFORMERS[:1], PerformerSpec("c3po_node", PERFORMERS[1].actions, {"move": 5.0})]


LAST_WORD = 300.0
"""Mission time of a cancel that ends a run still going then: without an at-start
timeout, an action whose requirement an event broke for good waits forever (as
PlanSys2's does), and so would the run. Every other run ends long before."""


def _observed(plan: str, event: str, at: float, options: ExecutorOptions) -> tuple[object, ...]:
    action = EVENTS[event]
    events: list[Event] = [] if action is None else [(at, action)]
    cancel = EVENTS["cancel"]
    assert cancel is not None
    events.append((LAST_WORD, cancel))
    return observe(PLANS[plan], SLOW_C3PO, options, events, _knowledge("(battery_full c3po)"))


def _park_on_any_move(self: PlanContext, rt: ActionRuntime, other: int, point: Point) -> None:
    self.active.discard(rt.index)


def _wake_on_every_move(self: PlanContext) -> None:
    """The general path: each action's dependents, woken on each of its moves."""
    for index, (start, end) in enumerate(zip(self.start_waits, self.end_waits, strict=True)):
        for other, _point in (*start, *end):
            waiting = self._on_move.setdefault(other, [])
            if index not in waiting:
                waiting.append(index)


@settings(max_examples=30, deadline=None)
@given(
    plan=st.sampled_from(sorted(PLANS)),
    event=st.sampled_from(sorted(EVENTS)),
    at=st.integers(0, 24).map(lambda n: n / 2),
    halt=st.booleans(),
    timeout=st.sampled_from([None, 3.0]),
    patrol_template=st.booleans(),
)
@example(plan="chain", event="cancel", at=3.0, halt=False, timeout=None, patrol_template=False)
@example(plan="cross", event="battery", at=3.0, halt=True, timeout=3.0, patrol_template=False)
@example(plan="cross", event="corridor", at=0.0, halt=False, timeout=None, patrol_template=False)
def test_waking_on_the_awaited_happening_matches_waking_on_every_move(
    plan: str, event: str, at: float, halt: bool, timeout: float | None, patrol_template: bool
) -> None:
    options = ExecutorOptions(
        halt_on_failure=halt,
        at_start_timeout=timeout,
        templates={"patrol": default_template} if patrol_template else {},
    )
    fast = _observed(plan, event, at, options)
    with pytest.MonkeyPatch.context() as m:
        m.setattr(PlanContext, "park_on", _park_on_any_move)
        m.setattr(PlanContext, "park_waiting", _wake_on_every_move)
        general = _observed(plan, event, at, options)
    assert fast == general


def test_a_parked_branch_wakes_on_what_it_waits_for_only() -> None:
    """In the chain each action starts after the one before ends: the second branch
    is not ticked when the first starts (only given RUNNING, as a tick would), and
    is active once the first ends; the third is not touched by either."""
    ctx = _context(PLAN)
    ctx.hub.publish = lambda *_a: None  # type: ignore[attr-defined]  # the info is not looked at
    root = build_tree(ctx)
    assert ctx.start_waits[1] == ((0, END),) and ctx.start_waits[2] == ((1, END),)
    assert ctx.active == {0} and not ctx.touched
    first, second, _third = ctx.actions
    ctx.action_started(first)
    assert ctx.active == {0} and ctx.touched == [1]
    ctx.active.discard(0)  # a tick that steps no branch (no performer here)
    root.tick_once()
    assert not ctx.touched
    assert [b.status.name for b in root.children] == ["INVALID", "RUNNING", "INVALID"]
    ctx.action_ended(first)
    assert ctx.active == {1}
    ctx.action_started(second)
    assert ctx.touched == [2] and ctx.active == {1}


def test_a_branch_parked_on_an_action_that_stops_is_woken() -> None:
    ctx = _context(PLAN)
    ctx.hub.publish = lambda *_a: None  # type: ignore[attr-defined]
    build_tree(ctx)
    ctx.park_on(ctx.actions[2], 0, START)
    ctx.actions[0].reason = "broken"
    ctx.action_finished(ctx.actions[0], success=False)
    assert {1, 2} <= ctx.active  # 1 waited for its end, 2 for its start
