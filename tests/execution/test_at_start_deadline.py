"""The at-start wait's deadline is registered when a wait begins, not before.

An at-start requirement that holds when the action's predecessors are done (nearly
every one) waits for nothing: it registers no deadline, which would otherwise wake
the executor ``at_start_timeout`` later for nothing. One that does not hold registers
one, at the moment its wait began plus the timeout, and still gives up then.
"""

from __future__ import annotations

from typing import Any

import pytest
from execution_helpers import knowledge_from, load_domain, run_scenario
from test_executor import SIMPLE_PERFORMERS, SIMPLE_PLAN

from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.plan_context import PlanContext
from plansys_bridge.execution.tree_builder import default_template
from plansys_bridge.knowledge.problem_expert import ProblemExpert


def _world() -> tuple[Any, ProblemExpert]:
    domain = load_domain("simple_example.pddl")
    k = knowledge_from(
        domain,
        instances={"r2d2": "robot", "kitchen": "room", "hall": "room"},
        facts=["(robot_at r2d2 kitchen)", "(connected kitchen hall)", "(battery_full r2d2)"],
    )
    return domain, k


def _cut(knowledge: ProblemExpert, _e: Executor) -> None:
    knowledge.remove_predicate("(connected kitchen hall)")


async def _execute(executor: Executor) -> Any:
    return await executor.execute(SIMPLE_PLAN)


def _deadlines(
    monkeypatch: pytest.MonkeyPatch, template: bool, events: list[Any]
) -> tuple[Any, list[tuple[float, float, int | None]]]:
    """Run the simple plan (its move waits for ``(connected kitchen hall)`` when cut)
    with a 3 s at-start timeout; every deadline an action registers, with when."""
    seen: list[tuple[float, float, int | None]] = []
    schedule = PlanContext.schedule

    def spy(self: PlanContext, deadline: float, owner: int | None = None) -> None:
        if owner is not None:
            seen.append((self.now(), deadline, owner))
        schedule(self, deadline, owner)

    monkeypatch.setattr(PlanContext, "schedule", spy)
    # template: the phases' subtree for every action (AtStartReqPhase's wait)
    options = ExecutorOptions(
        at_start_timeout=3.0,
        overrun_percentage=None,
        action_template=default_template if template else None,
    )
    domain, k = _world()
    run = run_scenario(domain, k, _execute, SIMPLE_PERFORMERS, options=options, events=events)
    return run.result, seen


@pytest.mark.parametrize("template", [False, True])
def test_a_requirement_that_holds_at_once_registers_no_deadline(
    template: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    result, seen = _deadlines(monkeypatch, template, [])
    assert result.success
    assert seen == []


@pytest.mark.parametrize("template", [False, True])
def test_a_wait_registers_its_deadline_when_it_begins_and_gives_up_then(
    template: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    result, seen = _deadlines(monkeypatch, template, [(1.0, _cut)])
    assert not result.success
    # the move's wait began when the first patrol ended (2.0): given up 3 s later
    assert [(round(t, 6), round(d, 6), owner) for t, d, owner in seen] == [(2.0, 5.0, 1)]
    move = result.actions[1]
    assert "did not hold within 3 s" in move.message
    assert result.finished == pytest.approx(5.0)
