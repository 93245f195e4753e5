"""The executor end to end on the virtual clock, with simulated performers on the hub."""

from __future__ import annotations

import asyncio
import itertools
from collections.abc import Iterator

import py_trees
import pytest
from execution_helpers import (
    PerformerSpec,
    Run,
    door_setup,
    knowledge_from,
    load_domain,
    overlap,
    per_robot_performers,
    run_scenario,
)

from plansys_bridge.errors import ExecutionError
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.execution.tree_builder import ActionNodes, TemplateError
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionExecutionInfo,
    ActionStatus,
    DotGraph,
    ExecutingPlan,
    ExecutionType,
    Topics,
)
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Domain
from plansys_bridge.planning.plan import Plan, parse_plan
from plansys_bridge.planning.planner import Planner

ALL_TOPICS = (
    Topics.ACTIONS_HUB,
    Topics.ACTION_EXECUTION_INFO,
    Topics.DOT_GRAPH,
    Topics.EXECUTING_PLAN,
)


def execute(plan: Plan, **kwargs: object):  # type: ignore[no-untyped-def]
    async def body(executor: Executor) -> ExecutionResult:
        return await executor.execute(plan, **kwargs)  # type: ignore[arg-type]

    return body


# ---------------------------------------------------------------- simple world


@pytest.fixture
def simple() -> Iterator[tuple[Domain, ProblemExpert]]:
    domain = load_domain("simple_example.pddl")
    k = knowledge_from(
        domain,
        instances={"r2d2": "robot", "kitchen": "room", "hall": "room", "dock": "room"},
        facts=[
            "(robot_at r2d2 kitchen)",
            "(connected kitchen hall)",
            "(connected hall kitchen)",
            "(connected kitchen dock)",
            "(connected dock kitchen)",
            "(charging_point_at dock)",
            "(battery_full r2d2)",
        ],
        goal="(and (patrolled kitchen) (patrolled hall))",
    )
    yield domain, k


SIMPLE_PERFORMERS = [
    PerformerSpec(
        "r2d2_node",
        {"move": ["r2d2"], "patrol": ["r2d2"], "askcharge": ["r2d2"], "charge": ["r2d2"]},
        {"move": 5.0, "patrol": 2.0, "askcharge": 5.0, "charge": 5.0},
        {"feedback_period": 1.0},
    )
]

SIMPLE_PLAN = parse_plan(
    "0.000: (patrol r2d2 kitchen) [2.000]\n"
    "2.001: (move r2d2 kitchen hall) [5.000]\n"
    "7.002: (patrol r2d2 hall) [2.000]\n"
)


def test_simple_plan_runs_in_order_with_feedback_info_and_dot(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple
    infos: list[ActionExecutionInfo] = []
    run = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN, goal=k.get_goal(), plan_id="p1", on_info=infos.append),
        SIMPLE_PERFORMERS,
        topics=ALL_TOPICS,
    )
    res = run.result
    assert res.success and res.status == "succeeded" and res.replans == 0
    assert [a.status for a in res.actions] == [ActionStatus.SUCCEEDED] * 3
    # each successor starts the very instant its predecessor's FINISH is processed
    assert [(a.start, a.end) for a in res.actions] == [(0.0, 2.0), (2.0, 7.0), (7.0, 9.0)]
    assert res.total_time == pytest.approx(9.0)
    assert res.efficiency_percent == pytest.approx(100.0)
    assert k.exist_predicate("(robot_at r2d2 hall)") and k.exist_predicate("(patrolled hall)")
    assert {a.performer for a in res.actions} == {"r2d2_node"}
    # ActionExecutionInfo: EXECUTING (with feedback) then SUCCEEDED for each action
    move_infos = [i for i in infos if i.action_full_name == "(move r2d2 kitchen hall)"]
    assert move_infos[0].status == ActionStatus.EXECUTING and move_infos[0].start_stamp == 2.0
    assert move_infos[-1].status == ActionStatus.SUCCEEDED and move_infos[-1].completion == 1.0
    assert any(0 < i.completion < 1 for i in move_infos)
    assert run.of_topic(Topics.ACTION_EXECUTION_INFO) == infos
    plans = run.of_topic(Topics.EXECUTING_PLAN)
    assert len(plans) == 1 and isinstance(plans[0], ExecutingPlan) and plans[0].plan_id == "p1"
    assert plans[0].plan == SIMPLE_PLAN.to_msg()
    dots = run.of_topic(Topics.DOT_GRAPH)
    assert isinstance(dots[-1], DotGraph) and dots[-1].plan_id == "p1"
    assert dots[-1].text.count("fillcolor=palegreen") == 3
    assert "ordered sub-goals" in dots[-1].text and "(patrolled hall)" in dots[-1].text
    # request ids keep auctions of different plans apart
    requests = [
        m
        for m in run.of_topic(Topics.ACTIONS_HUB)
        if isinstance(m, ActionExecution) and m.type == ExecutionType.REQUEST
    ]
    assert [m.request_id for m in requests] == ["p1/0/0", "p1/0/1", "p1/0/2"]


def test_rejected_plan_names_action_and_requirement(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    plan = parse_plan("0: (move r2d2 hall kitchen) [5]\n")
    run = run_scenario(domain, k, execute(plan), SIMPLE_PERFORMERS)
    assert not run.result.success and run.result.status == "rejected"
    assert "(move r2d2 hall kitchen)" in run.result.message
    assert "(robot_at r2d2 hall)" in run.result.message
    assert run.result.actions == []


def test_at_start_requirement_that_never_holds_fails_after_timeout(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple

    def cut(knowledge: ProblemExpert, _e: Executor) -> None:
        knowledge.remove_predicate("(connected kitchen hall)")

    run = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN),
        SIMPLE_PERFORMERS,
        options=ExecutorOptions(at_start_timeout=3.0),
        events=[(1.0, cut)],
    )
    res = run.result
    assert not res.success and res.status == "failed"
    move = res.actions[1]
    assert move.status == ActionStatus.FAILED and move.start is None
    assert "at start requirement (connected kitchen hall) did not hold within 3 s" in move.message
    assert res.actions[2].status == ActionStatus.NOT_EXECUTED
    assert "no planner" in res.message
    assert res.finished == pytest.approx(5.0)  # patrol ended at 2, gave up 3 s later


def test_at_start_requirement_restored_later_lets_the_action_start_at_once(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple

    def cut(knowledge: ProblemExpert, _e: Executor) -> None:
        knowledge.remove_predicate("(connected kitchen hall)")

    def restore(knowledge: ProblemExpert, _e: Executor) -> None:
        knowledge.add_predicate("(connected kitchen hall)")

    run = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN),
        SIMPLE_PERFORMERS,
        options=ExecutorOptions(at_start_timeout=3.0),
        events=[(1.0, cut), (3.5, restore)],
    )
    assert run.result.success
    assert run.result.actions[1].start == pytest.approx(3.5)  # woken by the knowledge change


def battery_drop(knowledge: ProblemExpert, _e: Executor) -> None:
    knowledge.remove_predicate("(battery_full r2d2)")


def test_over_all_violation_halts_the_action_and_replans(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple
    run = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN, goal=k.get_goal(), plan_id="bat"),
        SIMPLE_PERFORMERS,
        planner=Planner(timeout=20.0),
        events=[(4.0, battery_drop)],
        topics=ALL_TOPICS,
    )
    res = run.result
    assert res.success, res.message
    assert res.replans == 1 and len(res.plans) == 2
    first = [a for a in res.actions if a.plan_index == 0]
    assert first[0].status == ActionStatus.SUCCEEDED
    assert first[1].status == ActionStatus.FAILED
    assert "over all requirement (battery_full r2d2) no longer holds" in first[1].message
    assert first[1].end == pytest.approx(4.0)
    assert first[2].status == ActionStatus.NOT_EXECUTED
    # the performer of the halted move got a CANCEL at once
    cancels = [
        (t, m)
        for t, topic, m in run.messages
        if topic == Topics.ACTIONS_HUB
        and isinstance(m, ActionExecution)
        and m.type == ExecutionType.CANCEL
    ]
    assert [(t, m.request_id) for t, m in cancels] == [(4.0, "bat/0/1")]
    # the new plan recharges first, and the goal is reached
    second = [a.text for a in res.actions if a.plan_index == 1]
    assert any(t.startswith("(charge r2d2") for t in second)
    assert all(a.status == ActionStatus.SUCCEEDED for a in res.actions if a.plan_index == 1)
    assert k.is_goal_satisfied()
    assert len(run.of_topic(Topics.EXECUTING_PLAN)) == 2
    # the planner overlapped askcharge and charge, but r2d2 has one performer: charge's
    # REQUEST is repeated until it is free, and only the performer's work counts
    charge = next(a for a in res.actions if a.text == "(charge r2d2 dock)")
    assert charge.start == pytest.approx(4.0) and charge.confirmed == pytest.approx(9.0)
    assert charge.execution_time == pytest.approx(5.0)
    assert res.efficiency_percent <= 100.0
    text = res.summary()
    assert text.splitlines()[0].startswith("succeeded: ") and "1 replans" in text
    assert "[0] FAILED           2.00 ->     4.00  (move r2d2 kitchen hall)  by r2d2_node" in text
    assert "[0] NOT_EXECUTED" in text and "not started: the plan stopped after" in text


def test_halted_action_has_its_at_start_effects_undone(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple
    run = run_scenario(
        domain, k, execute(SIMPLE_PLAN), SIMPLE_PERFORMERS, events=[(4.0, battery_drop)]
    )
    assert run.result.status == "failed" and "no planner" in run.result.message
    # the move deleted (robot_at r2d2 kitchen) at its start; halted, it gets it back
    assert k.exist_predicate("(robot_at r2d2 kitchen)")
    assert not k.exist_predicate("(robot_at r2d2 hall)")


def test_replanning_budget_is_respected(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    run = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN, goal=k.get_goal()),
        SIMPLE_PERFORMERS,
        planner=Planner(timeout=20.0),
        options=ExecutorOptions(max_replans=0),
        events=[(4.0, battery_drop)],
    )
    assert run.result.status == "failed" and run.result.replans == 0
    assert "replanning budget of 0 used up" in run.result.message


def test_cancel_halts_running_actions_and_sends_cancel(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple

    def cancel(_k: ProblemExpert, executor: Executor) -> None:
        assert executor.running == ["c1"]
        executor.cancel("c1")

    run = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN, plan_id="c1"),
        SIMPLE_PERFORMERS,
        events=[(3.0, cancel)],
        topics=ALL_TOPICS,
    )
    res = run.result
    assert not res.success and res.status == "cancelled"
    assert [a.status for a in res.actions] == [
        ActionStatus.SUCCEEDED,
        ActionStatus.CANCELLED,
        ActionStatus.NOT_EXECUTED,
    ]
    assert res.finished == pytest.approx(3.0)
    kinds = [
        m.type
        for m in run.of_topic(Topics.ACTIONS_HUB)
        if isinstance(m, ActionExecution) and m.request_id == "c1/0/1"
    ]
    assert kinds[:3] == [ExecutionType.REQUEST, ExecutionType.RESPONSE, ExecutionType.CONFIRM]
    # (a FEEDBACK the performer sent in the same instant may cross the CANCEL)
    assert ExecutionType.CANCEL in kinds and ExecutionType.FINISH not in kinds
    assert set(kinds[kinds.index(ExecutionType.CANCEL) :]) <= {
        ExecutionType.CANCEL,
        ExecutionType.FEEDBACK,
    }
    assert k.exist_predicate("(robot_at r2d2 kitchen)")  # rolled back


def test_cancel_of_unknown_plan_is_an_error(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    executor = Executor.__new__(Executor)
    executor._executions = {}
    with pytest.raises(ExecutionError, match="no plan 'nope' is executing"):
        executor.cancel("nope")
    del domain, k


def test_overrun_fails_an_action_that_takes_too_long(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    slow = [
        PerformerSpec("slow", {"patrol": ["r2d2"], "move": ["r2d2"]}, {"patrol": 2.0, "move": 20.0})
    ]
    run = run_scenario(
        domain, k, execute(SIMPLE_PLAN), slow, options=ExecutorOptions(overrun_percentage=50.0)
    )
    move = run.result.actions[1]
    assert move.status == ActionStatus.FAILED
    assert "overran its planned duration 5 s by more than 50 %" in move.message
    assert move.end == pytest.approx(2.0 + 7.5)


def test_custom_template_replaces_an_action_subtree(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    seen: list[str] = []

    class Announce(py_trees.behaviour.Behaviour):
        def __init__(self, text: str) -> None:
            super().__init__(f"Announce {text}")
            self.text = text

        def update(self) -> py_trees.common.Status:
            seen.append(self.text)
            return py_trees.common.Status.SUCCESS

    def patrol_template(nodes: ActionNodes) -> py_trees.behaviour.Behaviour:
        return py_trees.composites.Sequence(
            f"custom {nodes.text}",
            memory=True,
            children=[
                nodes.wait_for_predecessors(),
                Announce(nodes.text),
                nodes.apply_at_start_effect(),
                nodes.running(),
                nodes.apply_at_end_effect(),
            ],
        )

    options = ExecutorOptions(templates={"patrol": patrol_template})
    run = run_scenario(domain, k, execute(SIMPLE_PLAN), SIMPLE_PERFORMERS, options=options)
    assert run.result.success
    assert seen == ["(patrol r2d2 kitchen)", "(patrol r2d2 hall)"]

    def broken(nodes: ActionNodes) -> py_trees.behaviour.Behaviour:
        return nodes.execute_action()

    k2 = knowledge_from(
        domain, instances={"r2d2": "robot", "kitchen": "room"}, facts=["(robot_at r2d2 kitchen)"]
    )
    with pytest.raises(
        TemplateError, match=r"template for action 'patrol'.*lacks WaitForPredecessors"
    ):
        run_scenario(
            domain,
            k2,
            execute(parse_plan("0: (patrol r2d2 kitchen) [2]\n")),
            SIMPLE_PERFORMERS,
            options=ExecutorOptions(action_template=broken),
        )


def test_missing_performer_gives_up_and_fails_cleanly(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    only_patrol = [PerformerSpec("p", {"patrol": ["r2d2"]}, {"patrol": 2.0})]
    options = ExecutorOptions(auction=ExecutorOptions().auction.__class__(give_up_after=3.0))
    run = run_scenario(domain, k, execute(SIMPLE_PLAN), only_patrol, options=options)
    move = run.result.actions[1]
    assert move.status == ActionStatus.FAILED
    assert (
        "no performer answered the REQUEST for (move r2d2 kitchen hall) within 3 s" in move.message
    )


# ---------------------------------------------------------------- factory: real parallelism


FACTORY_ROBOTS = ("robot1", "robot2", "robot3")


def run_factory(domain_file: str = "factory.pddl") -> tuple[Run, ProblemExpert]:
    domain = load_domain(domain_file)
    k = knowledge_from(domain, "problem_factory_1.pddl")
    plan = Planner(timeout=30.0).solve(domain, k.to_problem()).plan
    assert plan is not None
    performers = per_robot_performers(
        FACTORY_ROBOTS,
        ("move", "transport", "assemble"),
        {"move": 5.0, "transport": 5.0, "assemble": 5.0},
    )
    run = run_scenario(domain, k, execute(plan, goal=k.get_goal()), performers, topics=ALL_TOPICS)
    return run, k


def test_factory_runs_three_robots_in_parallel_with_specialised_performers() -> None:
    run, k = run_factory()
    res = run.result
    assert res.success, res.message
    assert k.is_goal_satisfied()
    for a in res.actions:
        robot = a.text.split()[1]
        assert a.performer.endswith("_" + robot), (a.text, a.performer)
    intervals = [(a.start, a.end) for a in res.actions if a.start is not None and a.end is not None]
    sequential = sum(e - s for s, e in intervals)
    assert overlap(intervals) > 0.5 * res.total_time
    assert res.total_time < sequential / 2
    assert res.efficiency_percent > 200.0
    # every robot's own actions never overlap (one performer per robot and action)
    for robot in FACTORY_ROBOTS:
        mine = sorted((a.start, a.end) for a in res.actions if a.text.split()[1] == robot)
        assert overlap(mine) == 0.0  # type: ignore[arg-type]


# ---------------------------------------------------------------- several plans at once


def test_two_plans_execute_at_once_independently(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    k.add_instance("c3po", "robot")
    k.add_predicate("(robot_at c3po hall)")
    k.add_predicate("(battery_full c3po)")
    plan_a = parse_plan("0: (patrol r2d2 kitchen) [2]\n2.001: (move r2d2 kitchen dock) [5]\n")
    plan_b = parse_plan("0: (patrol c3po hall) [2]\n2.001: (move c3po hall kitchen) [5]\n")
    performers = [
        *SIMPLE_PERFORMERS,
        PerformerSpec(
            "c3po_node", {"move": ["c3po"], "patrol": ["c3po"]}, {"move": 5.0, "patrol": 2.0}
        ),
    ]

    async def both(executor: Executor) -> ExecutionResult:
        a, b = await asyncio.gather(
            executor.execute(plan_a, plan_id="A"), executor.execute(plan_b, plan_id="B")
        )
        assert b.success and b.plan_id == "B"
        assert [x.request_id for x in b.actions] == ["B/0/0", "B/0/1"]
        assert overlap([(x.start, x.end) for x in a.actions + b.actions]) == pytest.approx(7.0)  # type: ignore[misc]
        return a

    run = run_scenario(domain, k, both, performers)
    assert run.result.success and [x.request_id for x in run.result.actions] == ["A/0/0", "A/0/1"]
    assert k.exist_predicate("(robot_at r2d2 dock)") and k.exist_predicate(
        "(robot_at c3po kitchen)"
    )


def test_same_plan_id_twice_is_refused(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple

    async def twice(executor: Executor) -> ExecutionResult:
        first = asyncio.ensure_future(executor.execute(SIMPLE_PLAN, plan_id="X"))
        await asyncio.sleep(0.5)
        with pytest.raises(ExecutionError, match="plan_id 'X' is already executing"):
            await executor.execute(SIMPLE_PLAN, plan_id="X")
        return await first

    assert run_scenario(domain, k, twice, SIMPLE_PERFORMERS).result.success


# ---------------------------------------------------------------- cooking


def test_cooking_two_robots_cook_two_dishes() -> None:
    import random

    from plansys_bridge.experiments.cooking_world import (
        PAPER_DURATIONS,
        ROBOT_ACTIONS,
        cooking_domain_path,
        dish_order,
        robot_names,
        world_setup,
    )
    from plansys_bridge.pddl.parser import parse_domain

    path = cooking_domain_path()
    domain = parse_domain(path.read_text(), str(path))
    setup = world_setup(2)
    order = dish_order(1, random.Random(7))
    k = knowledge_from(
        domain,
        instances={**setup.instances, **order.instances},
        facts=setup.predicates + order.predicates,
        goal=order.goal,
    )
    plan = Planner(timeout=30.0).solve(domain, k.to_problem()).plan
    assert plan is not None
    durations = {
        a: PAPER_DURATIONS["cook"] if a.startswith("cook") else PAPER_DURATIONS[a]
        for a in ROBOT_ACTIONS
    }
    performers = per_robot_performers(robot_names(2), ROBOT_ACTIONS, durations)
    run = run_scenario(domain, k, execute(plan, goal=k.get_goal()), performers)
    assert run.result.success, run.result.message
    assert k.is_goal_satisfied()
    assert run.result.efficiency_percent > 100.0


# ---------------------------------------------------------------- more cases


def test_performer_failures_replan_until_the_budget_is_used(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple
    failing = [
        PerformerSpec(
            "r2d2_node",
            {"move": ["r2d2"], "patrol": ["r2d2"]},
            {"move": 5.0, "patrol": 2.0},
            {"success_rate": 0.0},
        )
    ]
    run = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN, goal=k.get_goal()),
        failing,
        planner=Planner(timeout=20.0),
        options=ExecutorOptions(max_replans=2),
    )
    res = run.result
    assert res.status == "failed" and res.replans == 2 and len(res.plans) == 3
    assert "replanning budget of 2 used up" in res.message
    assert res.failures == 3  # the first action of each plan
    assert [a.plan_index for a in res.actions if a.status == ActionStatus.FAILED] == [0, 1, 2]


def test_plain_actions_use_preconditions_over_all_and_effects_at_end() -> None:
    from plansys_bridge.pddl.parser import parse_domain

    domain = parse_domain(
        """
        (define (domain walk)
          (:requirements :strips :typing)
          (:types robot place)
          (:predicates (at ?r - robot ?p - place) (road ?a ?b - place))
          (:action go
            :parameters (?r - robot ?a ?b - place)
            :precondition (and (at ?r ?a) (road ?a ?b))
            :effect (and (not (at ?r ?a)) (at ?r ?b))))
        """
    )
    k = knowledge_from(
        domain,
        instances={"bot": "robot", "p1": "place", "p2": "place", "p3": "place"},
        facts=["(at bot p1)", "(road p1 p2)", "(road p2 p3)"],
    )
    plan = parse_plan("0: (go bot p1 p2) [1]\n1: (go bot p2 p3) [1]\n")
    performers = [PerformerSpec("walker", {"go": ["bot"]}, {"go": 4.0})]

    def close_road(knowledge: ProblemExpert, _e: Executor) -> None:
        knowledge.remove_predicate("(road p2 p3)")

    ok = run_scenario(domain, k, execute(plan), performers)
    assert ok.result.success
    assert [(a.start, a.end) for a in ok.result.actions] == [(0.0, 4.0), (4.0, 8.0)]
    assert k.exist_predicate("(at bot p3)") and not k.exist_predicate("(at bot p1)")
    # the precondition is an over-all requirement: breaking it halts the action
    k2 = knowledge_from(
        domain,
        instances={"bot": "robot", "p1": "place", "p2": "place", "p3": "place"},
        facts=["(at bot p1)", "(road p1 p2)", "(road p2 p3)"],
    )
    broken = run_scenario(domain, k2, execute(plan), performers, events=[(6.0, close_road)])
    second = broken.result.actions[1]
    assert second.status == ActionStatus.FAILED and second.end == pytest.approx(6.0)
    assert "over all requirement (road p2 p3) no longer holds" in second.message
    assert k2.exist_predicate("(at bot p2)")  # a plain action changes nothing until its end


def test_executor_runs_on_the_wall_clock(simple: tuple[Domain, ProblemExpert]) -> None:
    from plansys_bridge.clock import WallClock, run
    from plansys_bridge.hub.hub import Hub
    from plansys_bridge.hub.transport import InProcessTransport
    from plansys_bridge.performers.base import PerformerContext
    from plansys_bridge.performers.simulated import SimulatedPerformer

    domain, k = simple
    clock = WallClock(time_scale=0.01)  # 9 s of mission in about 0.09 s

    async def main() -> ExecutionResult:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        spec = SIMPLE_PERFORMERS[0]
        perf = SimulatedPerformer(
            PerformerContext(hub, clock, k), spec.name, spec.actions, durations=spec.durations
        )
        await perf.start()
        try:
            return await Executor(hub, domain, k).execute(SIMPLE_PLAN)
        finally:
            await perf.stop()
            await hub.close()

    res = run(main(), clock)
    assert res.success
    # Never sooner than the plan allows; how much later depends on the machine's load
    # (a 10 ms stall is a whole second of mission time at this scale), so the upper
    # bound only catches a run that waited on something other than the actions.
    assert 9.0 - 0.01 <= res.total_time < 30.0
    starts = [a.start for a in res.actions]
    assert starts == sorted(starts)  # type: ignore[type-var]


def test_an_end_waits_for_the_happenings_it_must_follow() -> None:
    """hold_open closes the door at its end, so that end waits for pass to end,
    even when pass runs longer than planned (PlanSys2's CHECK_PREV_ACTIONS)."""
    domain, k = door_setup()
    plan = parse_plan("0.000: (hold_open holder d1) [10.000]\n0.001: (pass walker d1) [3.000]\n")
    performers = [
        PerformerSpec("holder", {"hold_open": ["holder"]}, {"hold_open": 10.0}),
        PerformerSpec("walker", {"pass": ["walker"]}, {"pass": 12.0}),
    ]
    seen: dict[float, bool] = {}

    def look(t: float):  # type: ignore[no-untyped-def]
        def probe(knowledge: ProblemExpert, _e: Executor) -> None:
            seen[t] = knowledge.exist_predicate("(door_open d1)")

        return (t, probe)

    infos: list[ActionExecutionInfo] = []
    run = run_scenario(
        domain, k, execute(plan, on_info=infos.append), performers, events=[look(11.0)]
    )
    hold, walk = run.result.actions
    assert run.result.success
    assert walk.start == hold.start == 0.0  # pass started with the door, not after it
    assert hold.end == pytest.approx(10.0) and walk.end == pytest.approx(12.0)
    assert seen == {11.0: True}  # hold_open's performer is done, its end effect waits
    done = {i.action_full_name: i.status_stamp for i in infos if i.status == ActionStatus.SUCCEEDED}
    assert done == {"(pass walker d1)": 12.0, "(hold_open holder d1)": 12.0}
    assert not k.exist_predicate("(door_open d1)")
    assert k.exist_predicate("(passed walker d1)")
    assert k.get_function("total-cost", ()) == pytest.approx(2.0)


def test_cancelled_action_gets_its_numeric_at_start_effects_back() -> None:
    domain = load_domain("domain_charging.pddl")
    k = knowledge_from(
        domain,
        instances={"r1": "robot", "wp1": "waypoint", "wp2": "waypoint"},
        facts=["(robot_at r1 wp1)", "(connected wp1 wp2)"],
        functions=[
            "(= (speed r1) 1)",
            "(= (max_range r1) 100)",
            "(= (state_of_charge r1) 50)",
            "(= (distance wp1 wp2) 10)",
        ],
    )
    plan = parse_plan("0: (move r1 wp1 wp2) [10]\n")
    seen: list[float | None] = []

    def probe(knowledge: ProblemExpert, _e: Executor) -> None:
        seen.append(knowledge.get_function("state_of_charge", ("r1",)))

    def cancel(_k: ProblemExpert, executor: Executor) -> None:
        executor.cancel()

    performers = [PerformerSpec("r1", {"move": ["r1"]}, {"move": 10.0})]
    run = run_scenario(domain, k, execute(plan), performers, events=[(2.0, probe), (4.0, cancel)])
    assert run.result.status == "cancelled"
    assert seen == [pytest.approx(40.0)]  # the at-start decrease was applied
    assert k.get_function("state_of_charge", ("r1",)) == pytest.approx(50.0)
    assert k.exist_predicate("(robot_at r1 wp1)")


def test_options_from_mission_sections_name_bad_keys() -> None:
    from plansys_bridge.errors import ConfigError

    opts = ExecutorOptions.from_config(
        {"at_start_timeout": 2.5, "overrun_percentage": 20},
        auction={"retry_period": 0.5},
        replanning={"max_replans": 5},
    )
    assert opts.at_start_timeout == 2.5 and opts.overrun_percentage == 20
    assert opts.auction.retry_period == 0.5 and opts.max_replans == 5
    with pytest.raises(ConfigError, match=r"execution\.at_start_timout"):
        ExecutorOptions.from_config({"at_start_timout": 1})
    with pytest.raises(ConfigError, match=r"replanning\.max_replans: must be >= 0"):
        ExecutorOptions.from_config({}, replanning={"max_replans": -1})
    with pytest.raises(ConfigError, match=r"execution\.overrun_percentage"):
        ExecutorOptions(overrun_percentage=-5)


def test_an_exception_in_a_template_stops_the_plan_and_its_performers(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    class Explode(py_trees.behaviour.Behaviour):
        def update(self) -> py_trees.common.Status:
            raise RuntimeError("sensor driver crashed")

    def move_template(nodes: ActionNodes) -> py_trees.behaviour.Behaviour:
        return py_trees.composites.Sequence(
            "exploding",
            memory=True,
            children=[
                nodes.wait_for_predecessors(),
                nodes.apply_at_start_effect(),
                nodes.running(),
                Explode("explode"),
                nodes.apply_at_end_effect(),
            ],
        )

    domain, k = simple
    k.add_instance("c3po", "robot")
    k.add_predicate("(robot_at c3po hall)")
    plan = parse_plan("0: (move r2d2 kitchen hall) [5]\n0: (patrol c3po hall) [20]\n")
    performers = [
        *SIMPLE_PERFORMERS,
        PerformerSpec("c3po_node", {"patrol": ["c3po"]}, {"patrol": 20.0}),
    ]
    with pytest.raises(RuntimeError, match="sensor driver crashed"):
        run_scenario(
            domain,
            k,
            execute(plan),
            performers,
            options=ExecutorOptions(templates={"move": move_template}),
        )


def test_a_dead_performer_is_replaced_and_the_record_says_so(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple
    plan = parse_plan("0: (patrol r2d2 kitchen) [2]\n")
    performers = [
        PerformerSpec(
            "dying", {"patrol": ["r2d2"]}, {"patrol": 2.0}, {"faults": {"die_rate": 1.0}}
        ),
        PerformerSpec("healthy", {"patrol": ["r2d2"]}, {"patrol": 2.0}),
    ]
    run = run_scenario(domain, k, execute(plan), performers)
    (patrol,) = run.result.actions
    assert run.result.success
    assert patrol.reauctioned == 1 and patrol.performer == "healthy"
    assert patrol.end is not None and patrol.end > 5.0  # the liveness timeout passed first


def test_dot_period_limits_dot_publications(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    every = run_scenario(
        domain,
        k,
        execute(SIMPLE_PLAN),
        SIMPLE_PERFORMERS,
        options=ExecutorOptions(dot_period=0.0),
        topics=ALL_TOPICS,
    )
    k2 = knowledge_from(
        domain,
        instances={"r2d2": "robot", "kitchen": "room", "hall": "room"},
        facts=["(robot_at r2d2 kitchen)", "(connected kitchen hall)", "(battery_full r2d2)"],
    )
    sparse = run_scenario(
        domain,
        k2,
        execute(SIMPLE_PLAN),
        SIMPLE_PERFORMERS,
        options=ExecutorOptions(dot_period=4.0),
        topics=ALL_TOPICS,
    )
    dot_times = [t for t, topic, _ in sparse.messages if topic == Topics.DOT_GRAPH]
    assert len(every.of_topic(Topics.DOT_GRAPH)) > len(dot_times) >= 2
    # the last one is the final state, published when the plan ends
    assert all(b - a >= 4.0 for a, b in itertools.pairwise(dot_times[:-1]))
    final = sparse.of_topic(Topics.DOT_GRAPH)[-1]
    assert isinstance(final, DotGraph) and final.text.count("fillcolor=palegreen") == 3


def test_an_empty_plan_for_an_unmet_goal_is_replanned(simple: tuple[Domain, ProblemExpert]) -> None:
    domain, k = simple
    done = run_scenario(domain, k, execute(Plan(), goal=k.get_goal()), SIMPLE_PERFORMERS)
    assert done.result.status == "failed" and "the plan ended without achieving the goal" in (
        done.result.message
    )
    replanned = run_scenario(
        domain,
        k,
        execute(Plan(), goal=k.get_goal()),
        SIMPLE_PERFORMERS,
        planner=Planner(timeout=20.0),
    )
    assert replanned.result.success and replanned.result.replans == 1
    assert len(replanned.result.plans[0]) == 0 and len(replanned.result.plans[1]) > 0
    assert k.is_goal_satisfied()


@pytest.mark.parametrize("halt", [False, True])
def test_after_a_failure_running_actions_finish_or_are_halted(
    simple: tuple[Domain, ProblemExpert], halt: bool
) -> None:
    domain, k = simple
    k.add_instance("c3po", "robot")
    k.add_predicate("(robot_at c3po hall)")
    plan = parse_plan("0: (move r2d2 kitchen hall) [5]\n0: (patrol c3po hall) [20]\n")
    performers = [
        *SIMPLE_PERFORMERS,
        PerformerSpec("c3po_node", {"patrol": ["c3po"]}, {"patrol": 20.0}),
    ]
    run = run_scenario(
        domain,
        k,
        execute(plan),
        performers,
        options=ExecutorOptions(halt_on_failure=halt),
        events=[(3.0, battery_drop)],
    )
    move, patrol = run.result.actions
    assert move.status == ActionStatus.FAILED and run.result.status == "failed"
    if halt:
        assert patrol.status == ActionStatus.CANCELLED and patrol.end == pytest.approx(3.0)
        assert patrol.message.startswith("halted: the plan stopped after (move r2d2")
        assert run.result.finished == pytest.approx(3.0)
        assert not k.exist_predicate("(patrolled hall)")
    else:
        assert patrol.status == ActionStatus.SUCCEEDED and patrol.end == pytest.approx(20.0)
        assert k.exist_predicate("(patrolled hall)")
    assert k.exist_predicate("(robot_at r2d2 kitchen)")


def test_factory4_sequential_classical_plan_is_run_in_parallel() -> None:
    """A classical planner orders everything; the graph finds what may overlap."""
    domain = load_domain("factory4.pddl")
    k = knowledge_from(domain, "problem_factory_1.pddl")
    for robot in FACTORY_ROBOTS:
        k.add_predicate(f"(battery_full {robot})")
    sequential = [
        "(move robot1 assembly_zone body_car_zone)",
        "(move robot2 assembly_zone steering_wheels_zone)",
        "(move robot3 assembly_zone wheels_zone)",
        "(transport robot1 body_car_1 body_car_zone assembly_zone)",
        "(transport robot2 steering_wheel_1 steering_wheels_zone assembly_zone)",
        "(transport robot3 wheel_1 wheels_zone assembly_zone)",
        "(assemble robot3 assembly_zone wheel_1 body_car_1 steering_wheel_1 car_1)",
    ]
    plan = parse_plan("".join(f"{i}: {a}\n" for i, a in enumerate(sequential)))
    names = ["move", "transport", "assemble"]
    performers = per_robot_performers(FACTORY_ROBOTS, names, dict.fromkeys(names, 5.0))
    run = run_scenario(domain, k, execute(plan), performers)
    res = run.result
    assert res.success, res.message
    assert [(a.start, a.end) for a in res.actions] == [
        (0.0, 5.0),
        (0.0, 5.0),
        (0.0, 5.0),
        (5.0, 10.0),
        (5.0, 10.0),
        (5.0, 10.0),
        (10.0, 15.0),
    ]
    assert k.exist_predicate("(car_assembled car_1)")


def test_result_as_plain_data(simple: tuple[Domain, ProblemExpert]) -> None:
    import json

    domain, k = simple
    res = run_scenario(domain, k, execute(SIMPLE_PLAN, plan_id="j"), SIMPLE_PERFORMERS).result
    data = json.loads(json.dumps(res.to_dict()))
    assert data["status"] == "succeeded" and data["plan_id"] == "j"
    assert data["plans"] == [SIMPLE_PLAN.to_text()]
    assert data["actions"][1]["status"] == "SUCCEEDED"
    assert data["actions"][1]["execution_time"] == pytest.approx(5.0)
    assert data["efficiency_percent"] == pytest.approx(100.0)


def test_cancelling_the_execute_task_stops_performers_and_rolls_back(
    simple: tuple[Domain, ProblemExpert],
) -> None:
    domain, k = simple

    async def with_timeout(executor: Executor) -> ExecutionResult:
        with pytest.raises(TimeoutError):
            await asyncio.wait_for(executor.execute(SIMPLE_PLAN, plan_id="t"), 4.0)
        assert executor.running == []
        await asyncio.sleep(0.1)  # let the CANCEL reach the performer
        return ExecutionResult(success=True, status="checked")

    run = run_scenario(domain, k, with_timeout, SIMPLE_PERFORMERS, topics=ALL_TOPICS)
    assert run.result.status == "checked"
    cancels = [
        m.request_id
        for m in run.of_topic(Topics.ACTIONS_HUB)
        if isinstance(m, ActionExecution) and m.type == ExecutionType.CANCEL
    ]
    assert cancels == ["t/0/1"]
    assert k.exist_predicate("(robot_at r2d2 kitchen)") and k.exist_predicate("(patrolled kitchen)")
