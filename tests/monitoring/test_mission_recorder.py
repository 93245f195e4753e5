"""The mission recorder: hub traffic and telemetry to a ROS 2 MCAP bag, read back."""

from __future__ import annotations

import math
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from plansys_bridge.clock import run
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.hub import Hub
from plansys_bridge.monitoring import msgs
from plansys_bridge.monitoring.recorder import MissionRecorder, RecorderError


def _read(bag: Path) -> list[tuple[str, str, int, Any]]:
    with AnyReader([bag]) as reader:
        return [
            (c.topic, c.msgtype, t, reader.deserialize(raw, c.msgtype))
            for c, t, raw in reader.messages()
        ]


def test_constants_match_the_hub_enums() -> None:
    types = msgs.hub_typestore().types
    execution: Any = types[msgs.ACTION_EXECUTION]
    for kind in hm.ExecutionType:
        assert getattr(execution, kind.name) == kind.value
    info: Any = types[msgs.ACTION_EXECUTION_INFO]
    for status in hm.ActionStatus:
        assert getattr(info, status.name) == status.value
    performer: Any = types[msgs.ACTION_PERFORMER_STATUS]
    for state in hm.PerformerState:
        assert getattr(performer, state.name) == state.value


def test_every_hub_message_is_recorded_as_its_plansys2_type(
    virtual_hub: Hub, tmp_path: Path
) -> None:
    bag = tmp_path / "run"
    plan = hm.Plan(
        (hm.PlanItem(0.0, "(move r2d2 a b)", 5.0), hm.PlanItem(5.001, "(pick r2d2 o)", 2.5))
    )

    async def main() -> None:
        await virtual_hub.start()
        with MissionRecorder(virtual_hub, bag) as recorder:
            virtual_hub.publish(
                hm.Topics.ACTIONS_HUB,
                hm.ActionExecution(
                    hm.ExecutionType.REQUEST, "", "move", ("r2d2", "a", "b"), request_id="p/0"
                ),
            )
            virtual_hub.publish(
                hm.Topics.ACTIONS_HUB,
                hm.ActionExecution(
                    hm.ExecutionType.RESPONSE,
                    "nav",
                    "move",
                    ("r2d2", "a", "b"),
                    bid=4.5,
                    request_id="p/0",
                ),
            )
            await virtual_hub.clock.sleep(2.5)
            virtual_hub.publish(
                hm.Topics.ACTION_EXECUTION_INFO,
                hm.ActionExecutionInfo(
                    hm.ActionStatus.EXECUTING,
                    0.25,
                    2.5,
                    "(move r2d2 a b)",
                    "move",
                    ("r2d2", "a", "b"),
                    5.75,
                    0.5,
                    "half",
                ),
            )
            virtual_hub.publish(
                hm.Topics.PERFORMERS_STATUS,
                hm.ActionPerformerStatus(
                    2.5, hm.PerformerState.RUNNING, "move", ("r2d2", ""), "nav"
                ),
            )
            virtual_hub.publish(hm.Topics.EXECUTING_PLAN, hm.ExecutingPlan(plan, "plan-7"))
            virtual_hub.publish(
                hm.Topics.KNOWLEDGE,
                hm.Knowledge(
                    ("r2d2", "a", "b"),
                    ("(robot_at r2d2 a)",),
                    ("(= (battery r2d2) 80)",),
                    "(and (robot_at r2d2 b))",
                ),
            )
            virtual_hub.publish(hm.Topics.DOT_GRAPH, hm.DotGraph("digraph plan {}", "plan-7"))
            await virtual_hub.clock.sleep(0.1)
            summary = recorder.summary()
        await virtual_hub.close()
        assert summary["/actions_hub"] == 2 and summary["/plansys_bridge/actions_hub"] == 2

    run(main(), virtual_hub.clock)
    records = _read(bag)
    by_topic: dict[str, list[tuple[str, int, Any]]] = {}
    for topic, msgtype, t, msg in records:
        by_topic.setdefault(topic, []).append((msgtype, t, msg))

    (t1, _, request), (t2, _, response) = by_topic["/actions_hub"]
    assert t1 == msgs.ACTION_EXECUTION and t2 == msgs.ACTION_EXECUTION
    assert (
        request.type == 1
        and list(request.arguments) == ["r2d2", "a", "b"]
        and request.node_id == ""
    )
    assert response.type == 2 and response.node_id == "nav"
    (_, _, ext_req), (_, _, ext_resp) = by_topic["/plansys_bridge/actions_hub"]
    assert (ext_req.request_id, ext_req.has_bid) == ("p/0", False)
    assert (ext_resp.has_bid, ext_resp.bid, ext_resp.execution.type) == (True, 4.5, 2)

    [(msgtype, stamp, info)] = by_topic["/action_execution_info"]
    assert msgtype == msgs.ACTION_EXECUTION_INFO
    assert stamp == 2_500_000_000  # log time = mission time of the virtual clock
    assert (info.start_stamp.sec, info.start_stamp.nanosec) == (0, 250_000_000)
    assert (info.duration.sec, info.duration.nanosec) == (5, 750_000_000)
    assert (
        info.status == 2 and info.completion == pytest.approx(0.5) and info.message_status == "half"
    )

    [(_, _, status)] = by_topic["/performers_status"]
    assert status.state == 2 and list(status.specialized_arguments) == ["r2d2", ""]
    assert status.node_name == "nav"

    [(msgtype, _, ros_plan)] = by_topic["/executing_plan"]
    assert msgtype == msgs.PLAN
    assert [(i.action, i.time, i.duration) for i in ros_plan.items] == [
        ("(move r2d2 a b)", 0.0, 5.0),
        ("(pick r2d2 o)", pytest.approx(5.001), 2.5),
    ]
    [(_, _, ext_plan)] = by_topic["/plansys_bridge/executing_plan"]
    assert ext_plan.plan_id == "plan-7" and len(ext_plan.plan.items) == 2

    [(msgtype, _, knowledge)] = by_topic["/problem_expert/knowledge"]
    assert msgtype == msgs.KNOWLEDGE
    assert list(knowledge.functions) == ["(= (battery r2d2) 80)"]
    assert knowledge.goal == "(and (robot_at r2d2 b))"
    [(msgtype, _, dot)] = by_topic["/dot_graph"]
    assert msgtype == msgs.STRING and dot.data == "digraph plan {}"


def test_telemetry_api(virtual_hub: Hub, tmp_path: Path) -> None:
    bag = tmp_path / "run"
    with MissionRecorder(virtual_hub, bag, topics=()) as recorder:
        recorder.record_pose("/drone/pose", 12.5, 1.0, -2.0, 30.0, math.radians(90))
        recorder.record_navsatfix("/drone/fix", 12.5, -35.3632, 149.1652, 584.0)
        battery: Any = recorder.store.types["sensor_msgs/msg/BatteryState"]
        msg = battery(
            header=recorder.header(12.0, "base"),
            voltage=12.6,
            temperature=20.0,
            current=-1.5,
            charge=2.0,
            capacity=2.2,
            design_capacity=2.2,
            percentage=0.8,
            power_supply_status=2,
            power_supply_health=1,
            power_supply_technology=3,
            present=True,
            cell_voltage=_floats([4.2, 4.2, 4.2]),
            cell_temperature=_floats([]),
            location="",
            serial_number="",
        )
        recorder.record("/battery", "sensor_msgs/msg/BatteryState", msg, 12.0)
        with pytest.raises(RecorderError, match="unknown message type acme/msg/Thing"):
            recorder.record_cdr("/thing", "acme/msg/Thing", b"\x00\x01\x00\x00")
    records = {topic: (t, msg) for topic, _, t, msg in _read(bag)}
    t, pose = records["/drone/pose"]
    assert t == 12_500_000_000
    assert (pose.pose.position.x, pose.pose.position.y, pose.pose.position.z) == (1.0, -2.0, 30.0)
    q = pose.pose.orientation
    assert math.atan2(2 * q.w * q.z, 1 - 2 * q.z * q.z) == pytest.approx(math.radians(90))
    assert (pose.header.stamp.sec, pose.header.stamp.nanosec) == (12, 500_000_000)
    _, fix = records["/drone/fix"]
    assert (fix.latitude, fix.longitude, fix.altitude) == (-35.3632, 149.1652, 584.0)
    _, batt = records["/battery"]
    assert batt.percentage == pytest.approx(0.8) and list(batt.cell_voltage) == pytest.approx(
        [4.2] * 3
    )
    with pytest.raises(RecorderError, match="not recording"):
        recorder.record_pose("/drone/pose", 13.0, 0.0, 0.0)


def _floats(values: list[float]) -> Any:
    return np.array(values, dtype=np.float32)


def test_adapters_may_record_from_their_threads(virtual_hub: Hub, tmp_path: Path) -> None:
    bag = tmp_path / "run"

    async def main() -> None:
        await virtual_hub.start()
        with MissionRecorder(virtual_hub, bag) as recorder:

            def telemetry(n: int) -> None:
                for i in range(200):
                    recorder.record_pose(f"/robot{n}/pose", i * 0.1, float(i), float(n))

            threads = [
                threading.Thread(target=telemetry, args=(n,), name=f"tel{n}") for n in range(3)
            ]
            for t in threads:
                t.start()
            for i in range(200):
                virtual_hub.publish(
                    hm.Topics.PERFORMERS_STATUS,
                    hm.ActionPerformerStatus(float(i), hm.PerformerState.READY, "move", (), "nav"),
                )
                await virtual_hub.clock.sleep(0.01)
            for t in threads:
                t.join()
        await virtual_hub.close()

    run(main(), virtual_hub.clock)
    topics = [topic for topic, _, _, _ in _read(bag)]
    for n in range(3):
        assert topics.count(f"/robot{n}/pose") == 200
    assert topics.count("/performers_status") == 200


def test_bag_opens_with_the_mcap_reader(virtual_hub: Hub, tmp_path: Path) -> None:
    bag = tmp_path / "run"

    async def main() -> None:
        await virtual_hub.start()
        with MissionRecorder(virtual_hub, bag):
            virtual_hub.publish(
                hm.Topics.ACTIONS_HUB,
                hm.ActionExecution(hm.ExecutionType.CANCEL, "nav", "move", ("r",)),
            )
            await virtual_hub.clock.sleep(0.1)
        await virtual_hub.close()

    run(main(), virtual_hub.clock)
    [mcap_file] = bag.glob("*.mcap")
    with mcap_file.open("rb") as f:
        reader = make_reader(f)
        [(schema, channel, message)] = [
            m for m in reader.iter_messages() if m[1].topic == "/actions_hub"
        ]
    assert schema is not None and schema.name == msgs.ACTION_EXECUTION
    assert schema.encoding == "ros2msg"
    text = schema.data.decode()
    assert "int16 CANCEL=7" in text.replace(" = ", "=") and "string[] arguments" in text
    assert channel.message_encoding == "cdr"
    # CDR header (little endian) then the int16 type field = 7
    assert message.data[:4] == b"\x00\x01\x00\x00" and message.data[4:6] == (7).to_bytes(
        2, "little"
    )


def test_existing_path_is_refused(virtual_hub: Hub, tmp_path: Path) -> None:
    (tmp_path / "run").mkdir()
    with pytest.raises(RecorderError, match=str(tmp_path / "run")):
        MissionRecorder(virtual_hub, tmp_path / "run").start()


def test_closing_unsubscribes_and_foreign_objects_are_skipped(
    virtual_hub: Hub, tmp_path: Path
) -> None:
    bag = tmp_path / "run"

    async def main() -> MissionRecorder:
        await virtual_hub.start()
        recorder = MissionRecorder(virtual_hub, bag).start()
        virtual_hub.publish(hm.Topics.DOT_GRAPH, {"not": "a hub message"})
        virtual_hub.publish(hm.Topics.DOT_GRAPH, hm.DotGraph("digraph {}"))
        await virtual_hub.clock.sleep(0.1)
        recorder.close()
        recorder.close()  # idempotent
        virtual_hub.publish(hm.Topics.DOT_GRAPH, hm.DotGraph("digraph late {}"))
        await virtual_hub.clock.sleep(0.1)
        await virtual_hub.close()
        return recorder

    recorder = run(main(), virtual_hub.clock)
    assert recorder.dropped == 1
    assert [msg.data for _, _, _, msg in _read(bag)] == ["digraph {}"]
