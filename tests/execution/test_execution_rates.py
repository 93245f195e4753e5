"""Rate limits of what the executor reports, on the virtual clock: FEEDBACK infos at
most once per ``info_period`` per action (status changes always), the DOT graph at
most once per ``dot_period``, and the kept DOT text equal to a freshly written one."""

from __future__ import annotations

import itertools
from collections.abc import Awaitable, Callable

import pytest
from execution_helpers import PerformerSpec, run_scenario

from plansys_bridge.errors import ConfigError
from plansys_bridge.execution.dot import IncrementalDot, plan_graph_to_dot
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.hub.messages import ActionExecutionInfo, ActionStatus, DotGraph, Topics
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.planning.plan import Plan, parse_plan
from plansys_bridge.planning.plan_graph import build_plan_graph

DOMAIN = """
(define (domain corridor)
  (:requirements :typing :durative-actions)
  (:types robot room)
  (:predicates (at ?r - robot ?x - room) (next ?a ?b - room))
  (:durative-action move
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration 5)
    :condition (and (at start (at ?r ?a)) (over all (next ?a ?b)))
    :effect (and (at start (not (at ?r ?a))) (at end (at ?r ?b)))))
"""

PLAN = parse_plan(
    "0.000: (move r1 a b) [5.000]\n5.001: (move r1 b c) [5.000]\n0.000: (move r2 a b) [5.000]\n"
)


def _world() -> tuple[Domain, ProblemExpert]:
    domain = parse_domain(DOMAIN, "<corridor>")
    k = ProblemExpert(domain)
    with k.transaction():
        for room in "abc":
            k.add_instance(room, "room")
        for robot in ("r1", "r2"):
            k.add_instance(robot, "robot")
            k.add_predicate(f"(at {robot} a)")
        k.add_predicate("(next a b)")
        k.add_predicate("(next b c)")
    return domain, k


PERFORMERS = [
    PerformerSpec(r, {"move": [r]}, {"move": 5.0}, {"feedback_period": 0.1}) for r in ("r1", "r2")
]


def _execute(plan: Plan) -> Callable[[Executor], Awaitable[ExecutionResult]]:
    async def body(executor: Executor) -> ExecutionResult:
        return await executor.execute(plan)

    return body


@pytest.mark.parametrize("period", [0.5, 2.0])
def test_feedback_infos_are_rate_limited_per_action_and_status_changes_are_not(
    period: float,
) -> None:
    domain, k = _world()
    run = run_scenario(
        domain,
        k,
        _execute(PLAN),
        PERFORMERS,
        options=ExecutorOptions(info_period=period),
        topics=(Topics.ACTION_EXECUTION_INFO,),
    )
    assert run.result.success
    by_action: dict[str, list[tuple[float, ActionExecutionInfo]]] = {}
    for t, _topic, info in run.messages:
        assert isinstance(info, ActionExecutionInfo)
        by_action.setdefault(info.action_full_name, []).append((t, info))
    assert len(by_action) == 3
    for infos in by_action.values():
        statuses = [i.status for _, i in infos]
        assert statuses[0] is ActionStatus.EXECUTING and statuses[-1] is ActionStatus.SUCCEEDED
        feedback_times = [t for t, i in infos[1:-1]]
        assert all(i.status is ActionStatus.EXECUTING for _, i in infos[1:-1])
        # ~50 FEEDBACKs over 5 s; published: one per period at most
        assert 1 <= len(feedback_times) <= 5 / period + 1
        assert all(b - a >= period - 1e-9 for a, b in itertools.pairwise(feedback_times))
        assert infos[-1][1].completion == 1.0


def test_every_feedback_is_published_with_a_zero_period() -> None:
    domain, k = _world()
    run = run_scenario(
        domain,
        k,
        _execute(PLAN),
        PERFORMERS,
        options=ExecutorOptions(info_period=0.0),
        topics=(Topics.ACTION_EXECUTION_INFO,),
    )
    assert len(run.messages) >= 3 * 40


def test_the_default_dot_period_limits_publications_and_the_last_is_final() -> None:
    domain, k = _world()
    run = run_scenario(domain, k, _execute(PLAN), PERFORMERS, topics=(Topics.DOT_GRAPH,))
    times = [t for t, _topic, _m in run.messages]
    assert all(b - a >= 1.0 for a, b in itertools.pairwise(times[:-1]))
    final = run.messages[-1][2]
    assert isinstance(final, DotGraph) and final.text.count("fillcolor=palegreen") == 3


def test_the_kept_dot_text_equals_a_freshly_written_one() -> None:
    domain, k = _world()
    graph = build_plan_graph(PLAN.sorted(), domain, k.state())
    dot = IncrementalDot(graph, name="p/0")
    first = dot.text()
    assert first == plan_graph_to_dot(graph, name="p/0")
    changes = [
        (0, ActionStatus.EXECUTING),
        (2, ActionStatus.EXECUTING),
        (0, ActionStatus.SUCCEEDED),
        (2, ActionStatus.FAILED),
        (1, ActionStatus.CANCELLED),
    ]
    statuses = [ActionStatus.NOT_EXECUTED] * 3
    for index, status in changes:
        dot.set_status(index, status)
        statuses[index] = status
        assert dot.text() == plan_graph_to_dot(graph, statuses, name="p/0")
    assert dot.text() != first


def test_the_kept_dot_text_of_a_long_plan_equals_a_freshly_written_one() -> None:
    """Changes in several blocks of node statements, some between two texts."""
    domain, k = _world()
    text = "".join(f"{10.0 * i:.3f}: (move r{1 + i % 2} a b) [5.000]\n" for i in range(150))
    graph = build_plan_graph(parse_plan(text), domain, k.state())
    dot = IncrementalDot(graph, name="long")
    statuses = [ActionStatus.NOT_EXECUTED] * 150
    rounds = [[0], [63, 64, 149], [1, 128], [127], [64, 65, 66, 0]]
    for n, indexes in enumerate(rounds):
        status = list(ActionStatus)[1 + n % 4]
        for index in indexes:
            dot.set_status(index, status)
            statuses[index] = status
        kept = dot.text()
        assert kept == plan_graph_to_dot(graph, statuses, name="long")
        for each in ActionStatus:  # independent of how the text is kept
            assert kept.count(f'] {each.name.lower()}"') == statuses.count(each)


def test_info_period_must_be_a_number() -> None:
    with pytest.raises(ConfigError) as err:
        ExecutorOptions.from_config({"info_period": -1})
    assert err.value.key == "execution.info_period"
