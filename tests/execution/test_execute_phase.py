"""ExecutePhase follows its action through the client's outcome future, without a task;
the executor must behave exactly as when a task awaited ``ActionClient.run()``.

The reference below is the task-based ``initialise`` ExecutePhase had before: same
records, same hub messages in the same order on every topic, same DOT, same
knowledge, whether the plan succeeds, is cancelled, halts after a failure or has its
``execute()`` task cancelled.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from typing import Any

import pytest
from execution_helpers import PerformerSpec, Run, knowledge_from, load_domain, run_scenario

from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.phases import ExecutePhase
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.messages import Topics
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.planning.plan import parse_plan

TOPICS = (
    Topics.ACTIONS_HUB,
    Topics.ACTION_EXECUTION_INFO,
    Topics.DOT_GRAPH,
    Topics.EXECUTING_PLAN,
)

PERFORMERS = [
    PerformerSpec(
        "r2d2_node",
        {"move": ["r2d2"], "patrol": ["r2d2"]},
        {"move": 5.0, "patrol": 2.0},
        {"feedback_period": 1.0},
    ),
    PerformerSpec("c3po_node", {"patrol": ["c3po"]}, {"patrol": 20.0}, {"feedback_period": 3.0}),
]

PLAN = parse_plan(
    "0.000: (patrol r2d2 kitchen) [2.000]\n"
    "0.000: (patrol c3po hall) [20.000]\n"
    "2.001: (move r2d2 kitchen hall) [5.000]\n"
    "7.002: (patrol r2d2 hall) [2.000]\n"
)


def _task_initialise(self: ExecutePhase) -> None:
    """ExecutePhase.initialise as it was: a task awaits ``ActionClient.run()``."""
    ctx, rt = self.ctx, self.rt
    self.client = ActionClient(
        ctx.hub,
        rt.step.action,
        rt.step.arguments,
        request_id=rt.record.request_id,
        policy=ctx.options.auction,
    )
    rt.client = self.client
    task = asyncio.get_running_loop().create_task(
        self.client.run(
            lambda c, s: ctx.feedback(rt, c, s),
            confirm_cb=lambda node: ctx.confirmed(rt, node),
        )
    )
    self.task = task
    ctx.tasks.add(task)
    task.add_done_callback(lambda _task: self._ended())


def _battery_drop(knowledge: ProblemExpert, _e: Executor) -> None:
    knowledge.remove_predicate("(battery_full r2d2)")


def _cancel(_k: ProblemExpert, executor: Executor) -> None:
    executor.cancel("p")


async def _execute(executor: Executor) -> ExecutionResult:
    return await executor.execute(PLAN, plan_id="p")


async def _execute_for_4s(executor: Executor) -> ExecutionResult:
    with contextlib.suppress(TimeoutError):
        await asyncio.wait_for(executor.execute(PLAN, plan_id="p"), 4.0)
    await asyncio.sleep(1.0)  # let the CANCELs reach the performers
    return ExecutionResult(success=True, status="timed out")


# The events come between two of the performers' feedbacks (every whole second), not
# at one: which of two things due at the same instant goes first is the loop's heap
# order, which any change in the number of loop callbacks or timers moves.
SCENARIOS: dict[str, tuple[Callable[..., Any], list[Any], ExecutorOptions]] = {
    "succeeds": (_execute, [], ExecutorOptions(max_replans=0)),
    "cancelled": (_execute, [(3.0005, _cancel)], ExecutorOptions(max_replans=0)),
    "failure": (_execute, [(4.0005, _battery_drop)], ExecutorOptions(max_replans=0)),
    "halted": (
        _execute,
        [(4.0005, _battery_drop)],
        ExecutorOptions(max_replans=0, halt_on_failure=True),
    ),
    "execute task cancelled": (_execute_for_4s, [], ExecutorOptions(max_replans=0)),
}


def _world() -> tuple[Any, ProblemExpert]:
    domain = load_domain("simple_example.pddl")
    k = knowledge_from(
        domain,
        instances={
            "r2d2": "robot",
            "c3po": "robot",
            "kitchen": "room",
            "hall": "room",
            "dock": "room",
        },
        facts=[
            "(robot_at r2d2 kitchen)",
            "(robot_at c3po hall)",
            "(connected kitchen hall)",
            "(connected hall kitchen)",
            "(battery_full r2d2)",
        ],
        goal="(and (patrolled kitchen) (patrolled hall))",
    )
    return domain, k


def _observe(name: str) -> tuple[Any, ...]:
    body, events, options = SCENARIOS[name]
    domain, k = _world()
    run: Run = run_scenario(
        domain, k, body, PERFORMERS, options=options, events=events, topics=TOPICS
    )
    return (
        run.result.to_dict(),
        [(round(t, 6), topic, repr(msg)) for t, topic, msg in run.messages],
        sorted(str(p) for p in k.get_predicates()),
    )


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_the_outcome_future_behaves_as_the_task_did(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    fast = _observe(name)
    with monkeypatch.context() as patch:
        patch.setattr(ExecutePhase, "initialise", _task_initialise)
        general = _observe(name)
    assert fast[0] == general[0]
    assert fast[1] == general[1]
    assert fast[2] == general[2]
    assert fast[1], "the scenario recorded no message"


def test_the_scenarios_reach_what_they_are_named_after() -> None:
    """So that the comparison above covers cancels and halts, not only successes."""
    results = {name: _observe(name)[0] for name in SCENARIOS}
    assert results["succeeds"]["status"] == "succeeded"
    assert results["cancelled"]["status"] == "cancelled"
    assert results["failure"]["failures"] == 1
    halted = [a["message"] for a in results["halted"]["actions"]]
    assert any(m.startswith("halted: the plan stopped after") for m in halted)
    cancels = [m for _, topic, m in _observe("execute task cancelled")[1] if "CANCEL" in m]
    assert cancels
