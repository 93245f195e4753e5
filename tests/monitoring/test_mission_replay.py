"""Reading recorded missions back, re-running plans, comparing outcomes."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.rosbag2 import StoragePlugin, Writer

from plansys_bridge.clock import run
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.hub import Hub
from plansys_bridge.mission_config import load_mission
from plansys_bridge.monitoring import msgs
from plansys_bridge.monitoring.recorder import MissionRecorder
from plansys_bridge.monitoring.replay import (
    MissionBagError,
    RecordedAction,
    RecordedMission,
    compare_missions,
    read_mission,
    replay_plan,
    rerun_mission,
)
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer

T = hm.ExecutionType
PLAN = hm.Plan(
    (
        hm.PlanItem(0.0, "(move r1 a b)", 3.0),
        hm.PlanItem(0.0, "(move r2 c d)", 4.0),
        hm.PlanItem(3.001, "(pick r1 o)", 2.0),
    )
)


def _exec(kind: T, node: str, text: str, rid: str = "", **kw: object) -> hm.ActionExecution:
    name, *args = text.strip("()").split()
    return hm.ActionExecution(kind, node, name, tuple(args), request_id=rid, **kw)  # type: ignore[arg-type]


def _record_traffic(hub: Hub, bag: Path) -> None:
    """A run in which: one action succeeds, one is re-auctioned then fails, one is cancelled."""
    steps: list[tuple[float, str, object]] = [
        (0.0, hm.Topics.EXECUTING_PLAN, hm.ExecutingPlan(PLAN, "p1")),
        (0.0, hm.Topics.ACTIONS_HUB, _exec(T.REQUEST, "", "(move r1 a b)", "p1/0")),
        (0.0, hm.Topics.ACTIONS_HUB, _exec(T.REQUEST, "", "(move r2 c d)", "p1/1")),
        (0.0, hm.Topics.ACTIONS_HUB, _exec(T.RESPONSE, "nav1", "(move r1 a b)", "p1/0")),
        (0.0, hm.Topics.ACTIONS_HUB, _exec(T.CONFIRM, "nav1", "(move r1 a b)", "p1/0")),
        (0.0, hm.Topics.ACTIONS_HUB, _exec(T.RESPONSE, "nav2", "(move r2 c d)", "p1/1")),
        (0.0, hm.Topics.ACTIONS_HUB, _exec(T.CONFIRM, "nav2", "(move r2 c d)", "p1/1")),
        (1.0, hm.Topics.ACTIONS_HUB, _exec(T.REQUEST, "", "(move r2 c d)", "p1/1")),  # re-sent
        (
            1.5,
            hm.Topics.ACTIONS_HUB,
            _exec(T.FEEDBACK, "nav1", "(move r1 a b)", "p1/0", completion=0.5),
        ),
        (
            3.0,
            hm.Topics.ACTIONS_HUB,
            _exec(
                T.FINISH,
                "nav1",
                "(move r1 a b)",
                "p1/0",
                success=True,
                completion=1.0,
                status="arrived",
            ),
        ),
        (3.0, hm.Topics.ACTIONS_HUB, _exec(T.REQUEST, "", "(pick r1 o)", "p1/2")),
        (3.0, hm.Topics.ACTIONS_HUB, _exec(T.CONFIRM, "arm", "(pick r1 o)", "p1/2")),
        # nav2 is lost: cancelled and the move re-auctioned to nav3, which fails
        (4.0, hm.Topics.ACTIONS_HUB, _exec(T.CANCEL, "nav2", "(move r2 c d)", "p1/1")),
        (4.0, hm.Topics.ACTIONS_HUB, _exec(T.CONFIRM, "nav3", "(move r2 c d)", "p1/1")),
        (
            4.5,
            hm.Topics.ACTIONS_HUB,
            _exec(T.FINISH, "nav2", "(move r2 c d)", "p1/1", success=True),
        ),  # stale
        (
            6.0,
            hm.Topics.ACTIONS_HUB,
            _exec(
                T.FINISH,
                "nav3",
                "(move r2 c d)",
                "p1/1",
                success=False,
                completion=0.25,
                status="blocked",
            ),
        ),
        (6.0, hm.Topics.ACTIONS_HUB, _exec(T.CANCEL, "arm", "(pick r1 o)", "p1/2")),
        (
            6.0,
            hm.Topics.ACTION_EXECUTION_INFO,
            hm.ActionExecutionInfo(
                hm.ActionStatus.FAILED, 0.0, 6.0, "(move r2 c d)", "move", ("r2", "c", "d")
            ),
        ),
    ]

    async def main() -> None:
        await hub.start()
        with MissionRecorder(hub, bag):
            for at, topic, msg in steps:
                delay = at - hub.clock.now()
                if delay > 0:
                    await hub.clock.sleep(delay)
                hub.publish(topic, msg)
            await hub.clock.sleep(0.1)
        await hub.close()

    run(main(), hub.clock)


def test_read_mission_rebuilds_every_action(virtual_hub: Hub, tmp_path: Path) -> None:
    _record_traffic(virtual_hub, tmp_path / "run")
    mission = read_mission(tmp_path / "run")
    assert mission.plan == PLAN
    by_action = {a.action: a for a in mission.actions}
    assert len(mission.actions) == 3
    move1 = by_action["(move r1 a b)"]
    assert (move1.performer, move1.outcome, move1.status) == ("nav1", "succeeded", "arrived")
    assert (move1.started, move1.finished, move1.duration) == (0.0, 3.0, 3.0)
    move2 = by_action["(move r2 c d)"]
    assert (move2.performer, move2.outcome, move2.status) == ("nav3", "failed", "blocked")
    assert move2.completion == pytest.approx(0.25) and move2.request_id == "p1/1"
    pick = by_action["(pick r1 o)"]
    assert (pick.performer, pick.outcome, pick.success) == ("arm", "cancelled", None)
    assert mission.final_info == {"(move r2 c d)": hm.ActionStatus.FAILED}
    assert not mission.succeeded
    assert mission.topics["/actions_hub"] == 16


def test_plansys2_bags_without_request_ids(tmp_path: Path) -> None:
    """A bag with only /actions_hub (as PlanSys2 itself records) is matched by action text."""
    store = msgs.hub_typestore()
    types = store.types
    path = tmp_path / "plansys2"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/actions_hub", msgs.ACTION_EXECUTION, typestore=store)
        for t, kind, node, success in [
            (1, 1, "", False),
            (2, 2, "robot1_move", False),
            (3, 3, "robot1_move", False),
            (9, 6, "robot1_move", True),
            (10, 1, "", False),  # the same action again, later
            (11, 3, "robot2_move", False),
            (15, 6, "robot2_move", False),
        ]:
            msg = types[msgs.ACTION_EXECUTION](
                type=kind, node_id=node, action="move", arguments=["r", "a", "b"],
                success=success, completion=1.0 if success else 0.0, status="",
            )  # fmt: skip
            writer.write(conn, t * 10**9, store.serialize_cdr(msg, msgs.ACTION_EXECUTION))
    mission = read_mission(path)
    assert mission.plan is None
    assert [(a.performer, a.outcome, a.started, a.finished) for a in mission.actions] == [
        ("robot1_move", "succeeded", 3.0, 9.0),
        ("robot2_move", "failed", 11.0, 15.0),
    ]


def _mission(*actions: RecordedAction, plan: hm.Plan = PLAN) -> RecordedMission:
    return RecordedMission(Path("x"), plans=[plan], actions=list(actions))


def _done(action: str, performer: str, success: bool, duration: float) -> RecordedAction:
    return RecordedAction(
        action, performer=performer, success=success, started=0.0, finished=duration
    )


def test_compare_missions_names_each_difference() -> None:
    base = _mission(
        _done("(move r1 a b)", "nav1", True, 3.0), _done("(move r2 c d)", "nav2", True, 4.0)
    )
    assert compare_missions(base, base).same
    assert str(compare_missions(base, base)) == "same plan, same performers, same outcomes"

    failed = _mission(
        _done("(move r1 a b)", "nav1", True, 3.0), _done("(move r2 c d)", "nav2", False, 4.0)
    )
    diff = compare_missions(base, failed)
    assert diff.differences == (
        "missing in re-run: (move r2 c d) by nav2 succeeded",
        "only in re-run: (move r2 c d) by nav2 failed",
    )
    slower = _mission(
        _done("(move r1 a b)", "nav1", True, 3.5), _done("(move r2 c d)", "nav2", True, 4.0)
    )
    assert compare_missions(base, slower).same
    assert compare_missions(base, slower, duration_tolerance=0.2).same
    assert compare_missions(base, slower, duration_tolerance=0.1).differences == (
        "duration of (move r1 a b): 3.000 s != 3.500 s",
    )
    other_plan = hm.Plan((PLAN.items[1], PLAN.items[0], PLAN.items[2]))
    assert "plan differs" in str(compare_missions(base, _mission(*base.actions, plan=other_plan)))
    shifted = hm.Plan((PLAN.items[0], PLAN.items[1], hm.PlanItem(3.5, "(pick r1 o)", 2.0)))
    assert "plan timing differs for (pick r1 o)" in str(
        compare_missions(base, _mission(*base.actions, plan=shifted))
    )


def test_truncated_mission_bag(virtual_hub: Hub, tmp_path: Path) -> None:
    _record_traffic(virtual_hub, tmp_path / "run")
    [mcap_file] = (tmp_path / "run").glob("*.mcap")
    data = mcap_file.read_bytes()
    mcap_file.write_bytes(data[: len(data) // 2])
    with pytest.raises(MissionBagError, match=str(tmp_path / "run")):
        read_mission(tmp_path / "run")
    with pytest.raises(MissionBagError, match="nothing"):
        read_mission(tmp_path / "nothing")


def test_replay_plan_runs_items_at_their_planned_times(virtual_hub: Hub, tmp_path: Path) -> None:
    async def main() -> list[RecordedAction]:
        await virtual_hub.start()
        context = PerformerContext(hub=virtual_hub, clock=virtual_hub.clock)
        performers = [
            SimulatedPerformer(context, "nav1", {"move": ["r1"]}, durations={"move": 3.0}),
            SimulatedPerformer(context, "nav2", {"move": ["r2"]}, durations={"move": 4.0}),
            SimulatedPerformer(context, "arm", {"pick": []}, durations={"pick": 2.0}),
        ]
        with MissionRecorder(virtual_hub, tmp_path / "rerun"):
            for p in performers:
                await p.start()
            try:
                records = await replay_plan(virtual_hub, PLAN)
            finally:
                for p in performers:
                    await p.stop()
        await virtual_hub.close()
        return records

    records = run(main(), virtual_hub.clock)
    assert [(r.action, r.performer, r.outcome) for r in records] == [
        ("(move r1 a b)", "nav1", "succeeded"),
        ("(move r2 c d)", "nav2", "succeeded"),
        ("(pick r1 o)", "arm", "succeeded"),
    ]
    assert records[2].started == pytest.approx(3.001, abs=1e-6)
    assert [r.duration for r in records] == pytest.approx([3.0, 4.0, 2.0], abs=0.01)
    mission = read_mission(tmp_path / "rerun")
    assert mission.plan == PLAN
    assert mission.final_info == dict.fromkeys(
        [i.action for i in PLAN.items], hm.ActionStatus.SUCCEEDED
    )
    assert compare_missions(mission, RecordedMission(Path("y"), [PLAN], records)).same


def test_planned_plan_is_the_fallback(virtual_hub: Hub, tmp_path: Path) -> None:
    """Without an executed plan, read_mission reports the plan written by record_plan."""
    with MissionRecorder(virtual_hub, tmp_path / "run", topics=()) as recorder:
        recorder.record_plan(PLAN, stamp=0.0)
    mission = read_mission(tmp_path / "run")
    assert mission.plan == PLAN and mission.topics == {"/plan": 1}
    assert mission.actions == [] and not mission.succeeded


def test_rerun_needs_a_recorded_plan(virtual_hub: Hub, tmp_path: Path) -> None:
    with MissionRecorder(virtual_hub, tmp_path / "empty", topics=()) as recorder:
        recorder.record_pose("/robot/pose", 0.0, 1.0, 2.0)
    mission = load_mission(Path(__file__).resolve().parents[2] / "configs" / "rosbag_replay.yaml")
    with pytest.raises(MissionBagError, match="holds no plan"):
        rerun_mission(mission, tmp_path / "empty", tmp_path / "rerun")
    assert not (tmp_path / "rerun").exists()
