"""What an action needed only while it ran is let go when it ends.

An ended action's auction client (with its outcome future and callbacks) and its
at-start change (kept to undo it if the action is halted before its end) are
dropped by the runtime, and the client has no cycles left: while a long plan runs,
the ended actions' objects are freed at once, not kept for the cyclic collector to
go through again and again until the plan ends.
"""

from __future__ import annotations

import gc
import weakref
from typing import Any

from execution_helpers import knowledge_from, load_domain, run_scenario
from test_executor import SIMPLE_PERFORMERS, SIMPLE_PLAN

from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.phases import ExecutePhase
from plansys_bridge.execution.plan_context import PlanContext


def test_ended_actions_let_their_client_and_start_change_go(monkeypatch: Any) -> None:
    domain = load_domain("simple_example.pddl")
    k = knowledge_from(
        domain,
        instances={"r2d2": "robot", "kitchen": "room", "hall": "room"},
        facts=["(robot_at r2d2 kitchen)", "(connected kitchen hall)", "(battery_full r2d2)"],
    )
    clients: list[weakref.ref[Any]] = []
    contexts: list[PlanContext] = []
    alive_at_end: list[int] = []
    initialise = ExecutePhase.initialise
    action_ended = PlanContext.action_ended

    def spy_initialise(self: ExecutePhase) -> None:
        initialise(self)
        clients.append(weakref.ref(self.client))
        contexts.append(self.ctx)

    def spy_ended(self: PlanContext, rt: Any) -> None:
        action_ended(self, rt)
        # the action just ended: the clients of the actions before it are gone
        alive_at_end.append(sum(ref() is not None for ref in clients[: rt.index]))

    monkeypatch.setattr(ExecutePhase, "initialise", spy_initialise)
    monkeypatch.setattr(PlanContext, "action_ended", spy_ended)

    async def body(executor: Executor) -> Any:
        return await executor.execute(SIMPLE_PLAN)

    gc.collect()
    gc.disable()
    try:
        run = run_scenario(domain, k, body, SIMPLE_PERFORMERS)
        assert run.result.success
        assert len(clients) == 3
        assert alive_at_end == [0, 0, 0]
        runtimes = contexts[0].actions
        assert [rt.client for rt in runtimes] == [None, None, None]
        assert [rt.start_delta for rt in runtimes] == [None, None, None]
    finally:
        gc.enable()
