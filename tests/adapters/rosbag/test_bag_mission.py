"""A whole mission on recorded navigation: planner, executor, bag performer, recorder.

Runs configs/rosbag_replay.yaml with the mission runner on the virtual clock (39 s
of moves cost no wall time), records it, reads the recording back, replays the
recorded plan with the same performers, and compares the outcomes.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from rosbag_testdata import REPO
from rosbags.highlevel import AnyReader

from plansys_bridge.mission import MissionReport, run_mission
from plansys_bridge.mission_config import load_mission
from plansys_bridge.monitoring.replay import (
    RecordedMission,
    compare_missions,
    read_mission,
    rerun_mission,
)

CONFIG = REPO / "configs" / "rosbag_replay.yaml"
RECORDED_DURATIONS = {
    "(move tiago kitchen livingroom)": 12.0,
    "(move tiago livingroom bedroom)": 14.0,
    "(move tiago bedroom bathroom)": 11.0,
    "(move tiago bathroom kitchen)": 13.0,
    "(move tiago kitchen bedroom)": 15.0,
}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, MissionReport]:
    """configs/rosbag_replay.yaml run by the mission runner, recorded to a bag."""
    bag = tmp_path_factory.mktemp("mission") / "run"
    mission = load_mission(CONFIG).model_copy(update={"record": str(bag)})
    report = run_mission(mission, out=None)
    return bag, report


def test_mission_runs_on_recorded_navigation(recorded: tuple[Path, MissionReport]) -> None:
    _, report = recorded
    assert report.success, report.summary()
    result = report.result
    assert result is not None
    moves = [s.text for s in result.plans[0].steps]
    assert moves and all(m.startswith("(move tiago ") for m in moves)
    # the run takes the recorded durations of the moves, back to back
    recorded_time = sum(RECORDED_DURATIONS[m] for m in moves)
    assert result.total_time == pytest.approx(recorded_time, abs=0.5)
    assert [a.performer for a in result.actions] == ["tiago_nav"] * len(moves)


def test_recorded_mission_opens_with_rosbags_and_mcap(
    recorded: tuple[Path, MissionReport],
) -> None:
    bag = recorded[0]
    with AnyReader([bag]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
    assert types["/actions_hub"] == "plansys2_msgs/msg/ActionExecution"
    assert types["/action_execution_info"] == "plansys2_msgs/msg/ActionExecutionInfo"
    assert types["/performers_status"] == "plansys2_msgs/msg/ActionPerformerStatus"
    assert types["/executing_plan"] == "plansys2_msgs/msg/Plan"
    assert types["/problem_expert/knowledge"] == "plansys2_msgs/msg/Knowledge"
    assert types["/dot_graph"] == "std_msgs/msg/String"
    assert types["/tiago_nav/pose"] == "nav_msgs/msg/Odometry"
    [mcap_file] = bag.glob("*.mcap")
    with mcap_file.open("rb") as f:
        mcap_reader = make_reader(f)
        summary = mcap_reader.get_summary()
        assert summary is not None
        schemas = {summary.schemas[c.schema_id].name for c in summary.channels.values()}
        assert {"plansys2_msgs/msg/ActionExecution", "plansys2_msgs/msg/Knowledge"} <= schemas
        assert all(c.message_encoding == "cdr" for c in summary.channels.values())
        topics = {channel.topic for _, channel, _ in mcap_reader.iter_messages()}
    assert "/actions_hub" in topics and not any(t.startswith("rt/") for t in topics)


def _rerun(first: RecordedMission, bag: Path, **overrides: Any) -> RecordedMission:
    """Replay ``first``'s plan with the mission's performers (changed by ``overrides``)."""
    return rerun_mission(load_mission(CONFIG), first, bag, performer_overrides=overrides)


def test_record_then_replay_gives_the_same_outcome(
    recorded: tuple[Path, MissionReport], tmp_path: Path
) -> None:
    bag, report = recorded
    assert report.result is not None
    plan = report.result.plans[0]
    first = read_mission(bag)
    assert first.plan is not None
    assert [i.action for i in first.plan.items] == [s.text for s in plan.steps]
    assert len(first.actions) == len(plan.steps)
    assert all(a.outcome == "succeeded" and a.performer == "tiago_nav" for a in first.actions)

    second = _rerun(first, tmp_path / "rerun")
    comparison = compare_missions(first, second, duration_tolerance=0.05)
    assert comparison.same, str(comparison)


def test_replay_with_a_changed_performer_is_reported(
    recorded: tuple[Path, MissionReport], tmp_path: Path
) -> None:
    first = read_mission(recorded[0])
    second = _rerun(first, tmp_path / "rerun", name="other_nav", rate=2.0)
    comparison = compare_missions(first, second, duration_tolerance=0.05)
    assert not comparison.same
    text = str(comparison)
    assert "missing in re-run: (move tiago" in text and "by other_nav succeeded" in text
    assert "duration of (move tiago" in text
    assert compare_missions(first, second, compare_performers=False).same


def test_replayed_pose_reaches_the_knowledge(recorded: tuple[Path, MissionReport]) -> None:
    """Knowledge snapshots in the bag follow the robot: in the bedroom at the end of move 1."""
    bag, report = recorded
    assert report.result is not None
    first_move = report.result.plans[0].steps[0]
    assert first_move.text == "(move tiago kitchen bedroom)"
    positions: list[tuple[float, float, float]] = []
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == "/problem_expert/knowledge"]
        for _, stamp, raw in reader.messages(conns):
            values = {}
            knowledge: Any = reader.deserialize(raw, conns[0].msgtype)
            for text in knowledge.functions:
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


def test_recorded_mission_decodes_with_mcap_ros2(recorded: tuple[Path, MissionReport]) -> None:
    """An independent CDR decoder (mcap-ros2-support) reads every message of the bag
    from the definitions embedded in it."""
    decoder = pytest.importorskip("mcap_ros2.decoder", reason="mcap-ros2-support not installed")
    bag, report = recorded
    [mcap_file] = bag.glob("*.mcap")
    first: dict[str, Any] = {}
    count = 0
    with mcap_file.open("rb") as f:
        reader = make_reader(f, decoder_factories=[decoder.DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages():
            first.setdefault(channel.topic, msg)
            count += 1
    assert count == sum(read_mission(bag).topics.values())
    request = first["/actions_hub"]
    assert (request.type, request.node_id, request.action) == (1, "", "move")
    assert first["/plansys_bridge/actions_hub"].request_id.endswith("/0")
    assert report.result is not None
    texts = [i.action for i in first["/executing_plan"].items]
    assert texts == [s.text for s in report.result.plans[0].steps]
    assert first["/performers_status"].node_name == "tiago_nav"
    assert "(robot_at tiago kitchen)" in first["/problem_expert/knowledge"].predicates
    assert first["/tiago_nav/pose"].child_frame_id == "base_footprint"
