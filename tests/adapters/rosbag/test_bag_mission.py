"""A whole mission on recorded navigation: planner, executor, bag performer, recorder.

Runs configs/rosbag_replay.yaml on the virtual clock (39 s of moves cost no wall time),
records it, reads the recording back, replays the recorded plan with the same
performers, and compares the outcomes.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from plansys_bridge_adapters.rosbag.performer import BagNavigationPerformer
from rosbag_testdata import REPO
from rosbags.highlevel import AnyReader

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import Topics
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.mission_config import MissionConfig, load_mission
from plansys_bridge.monitoring.recorder import MissionRecorder
from plansys_bridge.monitoring.replay import (
    RecordedMission,
    compare_missions,
    read_mission,
    replay_plan,
)
from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import ActionPerformer, PerformerContext
from plansys_bridge.performers.registry import performers_from_config
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.planner import Planner

CONFIG = REPO / "configs" / "rosbag_replay.yaml"


def _knowledge(mission: MissionConfig, domain: Domain) -> ProblemExpert:
    knowledge = ProblemExpert(domain)
    with knowledge.transaction():
        for name, type_name in mission.knowledge.instances.items():
            knowledge.add_instance(name, type_name)
        for fact in mission.knowledge.predicates:
            knowledge.add_predicate(fact)
        for value in mission.knowledge.functions:
            knowledge.set_function(value)
        assert mission.goal is not None
        knowledge.set_goal(mission.goal)
    return knowledge


@contextmanager
def _publish_knowledge(hub: Hub, knowledge: ProblemExpert) -> Iterator[None]:
    hub.publish(Topics.KNOWLEDGE, knowledge.to_msg())
    unsubscribe = knowledge.subscribe(
        lambda _change: hub.publish(Topics.KNOWLEDGE, knowledge.to_msg())
    )
    try:
        yield
    finally:
        unsubscribe()


def _performers(
    mission: MissionConfig,
    hub: Hub,
    knowledge: ProblemExpert | None,
    recorder: MissionRecorder,
    **overrides: Any,
) -> list[ActionPerformer]:
    entries = [dict(p.model_dump()) | overrides for p in mission.performers]
    context = PerformerContext(
        hub=hub, clock=hub.clock, knowledge=knowledge, base_dir=mission.base_dir, recorder=recorder
    )
    return performers_from_config(entries, context)


def _run_mission(bag: Path) -> tuple[ExecutionResult, Plan, ProblemExpert, list[ActionPerformer]]:
    mission = load_mission(CONFIG)
    domain = parse_domain_files(mission.domain_paths)
    knowledge = _knowledge(mission, domain)
    planned = Planner().solve(domain, knowledge.to_problem())
    assert planned.plan is not None, planned.message
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)

    async def main() -> tuple[ExecutionResult, list[ActionPerformer]]:
        await hub.start()
        recorder = MissionRecorder(hub, bag).start()
        performers = _performers(mission, hub, knowledge, recorder)
        try:
            for p in performers:
                await p.start()
            with _publish_knowledge(hub, knowledge):
                recorder.record_plan(_hub_plan(planned.plan))
                executor = Executor(hub, domain, knowledge, None, ExecutorOptions(max_replans=0))
                result = await executor.execute(planned.plan, goal=knowledge.get_goal())
        finally:
            for p in performers:
                await p.stop()
            recorder.close()
            await hub.close()
        return result, performers

    result, performers = run(main(), clock)
    return result, planned.plan, knowledge, performers


def _hub_plan(plan: Plan) -> Any:
    from plansys_bridge.hub.messages import Plan as HubPlan
    from plansys_bridge.hub.messages import PlanItem

    return HubPlan(tuple(PlanItem(s.time, s.text, s.duration) for s in plan.steps))


@pytest.fixture(scope="module")
def recorded(
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[Path, ExecutionResult, Plan, ProblemExpert, list[ActionPerformer]]:
    bag = tmp_path_factory.mktemp("mission") / "run"
    result, plan, knowledge, performers = _run_mission(bag)
    return bag, result, plan, knowledge, performers


def test_mission_runs_on_recorded_navigation(recorded: Any) -> None:
    _bag, result, plan, knowledge, performers = recorded
    assert result.success, result.message
    moves = [s.text for s in plan.steps]
    assert moves and all(m.startswith("(move tiago ") for m in moves)
    # the run takes the recorded durations of the moves, back to back
    recorded_time = sum(
        {
            "(move tiago kitchen livingroom)": 12.0,
            "(move tiago livingroom bedroom)": 14.0,
            "(move tiago bedroom bathroom)": 11.0,
            "(move tiago bathroom kitchen)": 13.0,
            "(move tiago kitchen bedroom)": 15.0,
        }[m]
        for m in moves
    )
    assert result.total_time == pytest.approx(recorded_time, abs=0.5)
    # the replayed pose reached the knowledge: the robot is back in the kitchen at (0, 0)
    assert knowledge.exist_predicate("(robot_at tiago kitchen)")
    assert knowledge.get_function("robot_x", ("tiago",)) == pytest.approx(0.0, abs=1e-6)
    assert knowledge.get_function("robot_y", ("tiago",)) == pytest.approx(0.0, abs=1e-6)
    [performer] = performers
    assert isinstance(performer, BagNavigationPerformer)
    assert performer.travelled > 20.0


def test_recorded_mission_opens_with_rosbags_and_mcap(recorded: Any) -> None:
    bag = recorded[0]
    with AnyReader([bag]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
    assert types["/actions_hub"] == "plansys2_msgs/msg/ActionExecution"
    assert types["/action_execution_info"] == "plansys2_msgs/msg/ActionExecutionInfo"
    assert types["/performers_status"] == "plansys2_msgs/msg/ActionPerformerStatus"
    assert types["/executing_plan"] == "plansys2_msgs/msg/Plan"
    assert types["/problem_expert/knowledge"] == "plansys2_msgs/msg/Knowledge"
    assert types["/dot_graph"] == "std_msgs/msg/String"
    assert types["/plan"] == "plansys2_msgs/msg/Plan"
    assert types["/tiago_nav/pose"] == "nav_msgs/msg/Odometry"
    [mcap_file] = bag.glob("*.mcap")
    with mcap_file.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        schemas = {summary.schemas[c.schema_id].name for c in summary.channels.values()}
        assert {"plansys2_msgs/msg/ActionExecution", "plansys2_msgs/msg/Knowledge"} <= schemas
        assert all(c.message_encoding == "cdr" for c in summary.channels.values())
        topics = {channel.topic for _, channel, _ in reader.iter_messages()}
    assert "/actions_hub" in topics and not any(t.startswith("rt/") for t in topics)


def _rerun(first: RecordedMission, bag: Path, **overrides: Any) -> RecordedMission:
    """Replay ``first``'s plan with the mission's performers (changed by ``overrides``)."""
    assert first.plan is not None
    plan = first.plan
    mission = load_mission(CONFIG)
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)

    async def rerun() -> None:
        await hub.start()
        recorder = MissionRecorder(hub, bag).start()
        performers = _performers(mission, hub, None, recorder, **overrides)
        try:
            for p in performers:
                await p.start()
            await replay_plan(hub, plan)
        finally:
            for p in performers:
                await p.stop()
            recorder.close()
            await hub.close()

    run(rerun(), clock)
    return read_mission(bag)


def test_record_then_replay_gives_the_same_outcome(recorded: Any, tmp_path: Path) -> None:
    bag, _result, plan, _, _ = recorded
    first = read_mission(bag)
    assert [i.action for i in first.plan.items] == [s.text for s in plan.steps]
    assert len(first.actions) == len(plan.steps)
    assert all(a.outcome == "succeeded" and a.performer == "tiago_nav" for a in first.actions)

    second = _rerun(first, tmp_path / "rerun")
    comparison = compare_missions(first, second, duration_tolerance=0.05)
    assert comparison.same, str(comparison)


def test_replay_with_a_changed_performer_is_reported(recorded: Any, tmp_path: Path) -> None:
    first = read_mission(recorded[0])
    second = _rerun(first, tmp_path / "rerun", name="other_nav", rate=2.0)
    comparison = compare_missions(first, second, duration_tolerance=0.05)
    assert not comparison.same
    text = str(comparison)
    assert "missing in re-run: (move tiago" in text and "by other_nav succeeded" in text
    assert "duration of (move tiago" in text
    assert compare_missions(first, second, compare_performers=False).same


def test_replayed_pose_reaches_the_knowledge(recorded: Any) -> None:
    """Knowledge snapshots in the bag follow the robot: in the bedroom at the end of move 1."""
    bag, _, plan, _, _ = recorded
    first_move = plan.steps[0]
    assert first_move.text == "(move tiago kitchen bedroom)"
    positions: list[tuple[float, float, float]] = []
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == "/problem_expert/knowledge"]
        for _, stamp, raw in reader.messages(conns):
            values = {}
            for text in reader.deserialize(raw, conns[0].msgtype).functions:
                m = re.fullmatch(r"\(= \((robot_[xy]) tiago\) (\S+)\)", text)
                if m:
                    values[m[1]] = float(m[2])
            positions.append((stamp / 1e9, values["robot_x"], values["robot_y"]))
    at_end_of_move = [(x, y) for t, x, y in positions if t == pytest.approx(first_move.duration)]
    assert (6.5, 6.0) in at_end_of_move  # bedroom, as recorded
    # updates once per mission second while moving, not once per pose
    assert 30 <= len(positions) <= 60
    xs = [x for _, x, _ in positions]
    assert max(xs) == pytest.approx(6.8, abs=0.1)  # through the door at x = 6.8
