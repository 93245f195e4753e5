"""The bag navigation performer, driven through the hub's auction on the virtual clock."""

from __future__ import annotations

import asyncio
import itertools
import math
import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pytest
from plansys_bridge_adapters.rosbag.errors import BagCorruptError, BagTopicError
from plansys_bridge_adapters.rosbag.performer import BagNavigationPerformer
from plansys_bridge_adapters.rosbag.reader import POSE_STAMPED, BagReader, PoseSample
from plansys_bridge_adapters.rosbag.route import Segment
from rosbag_testdata import ARDRONE, HUSKY, NAV2_AMCL, NAV2_ODOM, REPO, real_bag
from rosbags.highlevel import AnyReader

from plansys_bridge.clock import run
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.monitoring.recorder import MissionRecorder
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import ActionGoal, PerformerContext
from plansys_bridge.performers.registry import load_performer_kind

Feedback = list[tuple[float, float, str]]


def _performer(
    hub: Hub, base_dir: Path, recorder: object | None = None, **settings: Any
) -> BagNavigationPerformer:
    config: dict[str, Any] = {
        "kind": "rosbag",
        "name": "tiago_nav",
        "actions": {"move": ["tiago"]},
        "bag": "kitchen_nav",
        "topic": "/odom",
        "segments": "kitchen_nav.segments.yaml",
    }
    config.update(settings)
    context = PerformerContext(hub=hub, clock=hub.clock, base_dir=base_dir, recorder=recorder)
    [performer] = BagNavigationPerformer.from_config(config, context, key="performers[0]")
    assert isinstance(performer, BagNavigationPerformer)
    return performer


async def _move(
    hub: Hub, *args: str, policy: AuctionPolicy | None = None
) -> tuple[ActionOutcome, float, Feedback]:
    feedback: Feedback = []
    client = ActionClient(hub, "move", args, policy=policy)
    start = hub.clock.now()
    outcome = await client.run(lambda c, s: feedback.append((hub.clock.now(), c, s)))
    return outcome, hub.clock.now() - start, feedback


def test_entry_point_names_the_performer() -> None:
    assert load_performer_kind("rosbag") is BagNavigationPerformer


def test_move_replays_its_segment_in_recorded_time(virtual_hub: Hub, demo_bags: Path) -> None:
    async def main() -> None:
        performer = _performer(virtual_hub, demo_bags)
        async with performer:
            outcome, elapsed, feedback = await _move(virtual_hub, "tiago", "kitchen", "livingroom")
            pose = performer.pose
        assert outcome.success, outcome.status
        assert outcome.performer == "tiago_nav"
        assert "kitchen->livingroom" in outcome.status and "6.20 m" in outcome.status
        # 12 s recorded; the auction costs no mission time on an idle virtual clock
        assert elapsed == pytest.approx(12.0, abs=0.05)
        completions = [c for _, c, _ in feedback]
        assert completions[0] == pytest.approx(0.0, abs=1e-3)
        assert completions[-1] == pytest.approx(1.0)
        assert all(b >= a for a, b in itertools.pairwise(completions))
        # 10 Hz publication over 12 s
        assert 115 <= len(feedback) <= 122
        assert pose is not None and (pose.x, pose.y) == pytest.approx((6.0, 0.5))

    run(main(), virtual_hub.clock)


def test_rate_scales_the_replay(virtual_hub: Hub, demo_bags: Path) -> None:
    async def main() -> None:
        async with _performer(virtual_hub, demo_bags, rate=4.0):
            outcome, elapsed, _ = await _move(virtual_hub, "tiago", "kitchen", "bedroom")
        assert outcome.success
        assert elapsed == pytest.approx(15.0 / 4.0, abs=0.05)

    run(main(), virtual_hub.clock)


def test_ros1_bag_of_the_same_drive_gives_the_same_path(virtual_hub: Hub, demo_bags: Path) -> None:
    async def main() -> None:
        async with _performer(
            virtual_hub, demo_bags, bag="kitchen_nav_ros1.bag", topic="/robot_pose"
        ) as performer:
            outcome, elapsed, _ = await _move(virtual_hub, "tiago", "bedroom", "bathroom")
            assert isinstance(performer, BagNavigationPerformer)
            pose = performer.pose
        assert outcome.success and elapsed == pytest.approx(11.0, abs=0.05)
        assert pose is not None and pose.msgtype == "geometry_msgs/msg/PoseStamped"
        assert (pose.x, pose.y) == pytest.approx((1.0, 6.5))

    run(main(), virtual_hub.clock)


@pytest.mark.parametrize(
    ("source", "start", "end"),
    [(HUSKY, 20.0, 80.0), (ARDRONE, 30.0, 50.0), (NAV2_ODOM, 0.0, 40.0), (NAV2_AMCL, 40.0, 97.0)],
    ids=["husky-ros1", "ardrone-ros1", "nav2-mcap-odom", "nav2-mcap-amcl"],
)
def test_real_bag_segments_replay_through_the_auction(
    virtual_hub: Hub,
    tmp_path: Path,
    source: tuple[str, str],
    start: float,
    end: float,
) -> None:
    name, topic = source
    segments = [{"arguments": ["", "a", "b"], "start": start, "end": end, "name": "a->b"}]

    async def main() -> None:
        recorder = MissionRecorder(virtual_hub, tmp_path / "run").start()
        performer = _performer(
            virtual_hub,
            real_bag(name).parent,
            recorder,
            bag=name,
            topic=topic,
            segments=segments,
            actions={"move": ["robot"]},
        )
        try:
            async with performer:
                outcome, elapsed, feedback = await _move(virtual_hub, "robot", "a", "b")
                last = performer.pose
        finally:
            recorder.close()
        profile = performer.route.profile(performer.route.segments[0])
        assert outcome.success, outcome.status
        assert elapsed == pytest.approx(profile.duration, abs=0.05)
        assert profile.duration > 0.9 * (end - start) - 2.0
        assert feedback[-1][1] == pytest.approx(1.0)
        # the last replayed pose is the last pose of the window, read independently
        with BagReader(real_bag(name)) as bag:
            window = list(Segment(bag=real_bag(name), topic=topic, start=start, end=end).poses(bag))
        assert last is not None and last.bag_time_ns == window[-1].bag_time_ns
        assert (last.x, last.y, last.z) == (window[-1].x, window[-1].y, window[-1].z)
        # replayed messages reached the recorder as ROS 2 messages of the same type
        with AnyReader([tmp_path / "run"]) as reader:
            conns = [c for c in reader.connections if c.topic == "/tiago_nav/pose"]
            assert len(conns) == 1 and conns[0].msgtype == window[-1].msgtype
            replayed: list[Any] = [
                reader.deserialize(raw, conns[0].msgtype) for _, _, raw in reader.messages(conns)
            ]
        publish_rate_count = math.ceil(profile.duration * 10) + 1
        assert 0.9 * min(profile.count, publish_rate_count) <= len(replayed) <= publish_rate_count
        msg = replayed[-1]
        pose = msg.pose if last.msgtype == POSE_STAMPED else msg.pose.pose
        assert (pose.position.x, pose.position.y) == (last.x, last.y)

    run(main(), virtual_hub.clock)


def test_cancel_stops_the_replay(virtual_hub: Hub, demo_bags: Path) -> None:
    async def main() -> None:
        async with _performer(virtual_hub, demo_bags) as performer:
            client = ActionClient(virtual_hub, "move", ("tiago", "livingroom", "bedroom"))
            task = asyncio.ensure_future(client.run())
            await virtual_hub.clock.sleep(5.0)
            client.cancel()
            outcome = await task
            assert isinstance(performer, BagNavigationPerformer)
            await virtual_hub.clock.sleep(0.5)
            assert not performer.busy
            pose = performer.pose
        assert outcome.cancelled and not outcome.success
        assert 0.1 < outcome.completion < 0.6
        assert pose is not None and 0.5 < pose.y < 6.0  # stopped between the rooms

    run(main(), virtual_hub.clock)


def test_no_segment_no_answer(virtual_hub: Hub, demo_bags: Path) -> None:
    async def main() -> None:
        policy = AuctionPolicy(give_up_after=3.0)
        async with _performer(virtual_hub, demo_bags):
            outcome, _, _ = await _move(virtual_hub, "tiago", "kitchen", "garage", policy=policy)
        assert outcome.gave_up and not outcome.success

    run(main(), virtual_hub.clock)


def test_bid_is_the_recorded_duration(virtual_hub: Hub, demo_bags: Path) -> None:
    async def main() -> None:
        async with _performer(virtual_hub, demo_bags, rate=2.0) as performer:
            goal = ActionGoal("move", ("tiago", "livingroom", "bedroom"), "r1")
            assert performer.bid(goal) == pytest.approx(7.0)
            assert performer.bid(ActionGoal("move", ("tiago", "x", "y"), "r2")) == math.inf

    run(main(), virtual_hub.clock)


def test_bag_broken_after_start_fails_the_action(
    virtual_hub: Hub, demo_bags: Path, tmp_path: Path
) -> None:
    shutil.copytree(demo_bags / "kitchen_nav", tmp_path / "kitchen_nav")
    shutil.copy(demo_bags / "kitchen_nav.segments.yaml", tmp_path)
    mcap = tmp_path / "kitchen_nav" / "kitchen_nav.mcap"

    async def main() -> None:
        async with _performer(virtual_hub, tmp_path):
            data = mcap.read_bytes()
            mcap.write_bytes(data[: len(data) // 2])
            outcome, _, _ = await _move(virtual_hub, "tiago", "kitchen", "livingroom")
        assert not outcome.success
        assert "kitchen_nav" in outcome.status and "truncated or damaged" in outcome.status

    run(main(), virtual_hub.clock)


def test_truncated_bag_fails_at_start(virtual_hub: Hub, tmp_path: Path) -> None:
    data = (real_bag(HUSKY[0])).read_bytes()
    (tmp_path / HUSKY[0]).write_bytes(data[: len(data) // 3])

    async def main() -> None:
        performer = _performer(
            virtual_hub, tmp_path, bag=HUSKY[0], topic=HUSKY[1], segments=[{"end": 10.0}]
        )
        with pytest.raises(BagCorruptError, match=HUSKY[0]):
            await performer.start()
        assert not performer.running

    run(main(), virtual_hub.clock)


def test_wrong_topic_fails_at_start(virtual_hub: Hub, demo_bags: Path) -> None:
    async def main() -> None:
        performer = _performer(virtual_hub, demo_bags, topic="/odometry")
        with pytest.raises(BagTopicError, match="/odometry"):
            await performer.start()

    run(main(), virtual_hub.clock)


@pytest.mark.parametrize(
    ("settings", "key"),
    [
        ({"segments": None}, "performers[0].segments"),
        ({"rate": 0}, "performers[0].rate"),
        ({"publish_rate": "fast"}, "performers[0].publish_rate"),
        ({"knowledge": {"functions": {"heading": "h"}}}, "performers[0].knowledge.functions"),
        (
            {"knowledge": {"functions": {"x": "rx"}, "robot_argument": -1}},
            "performers[0].knowledge.robot_argument",
        ),
        ({"speed": 2}, "performers[0].speed"),
        ({"topic": 5}, "performers[0].topic"),
    ],
)
def test_config_errors_name_the_key(
    virtual_hub: Hub, demo_bags: Path, settings: Mapping[str, Any], key: str
) -> None:
    with pytest.raises(ConfigError) as err:
        _performer(virtual_hub, demo_bags, **settings)
    assert err.value.key == key


def test_missing_segments_key(virtual_hub: Hub, demo_bags: Path) -> None:
    context = PerformerContext(hub=virtual_hub, clock=virtual_hub.clock, base_dir=demo_bags)
    config = {"kind": "rosbag", "name": "n", "actions": {"move": []}, "bag": "kitchen_nav"}
    with pytest.raises(ConfigError) as err:
        BagNavigationPerformer.from_config(config, context, key="performers[3]")
    assert err.value.key == "performers[3].segments"


def test_replayed_poses_are_published_on_the_hub(virtual_hub: Hub, demo_bags: Path) -> None:
    received: list[PoseSample] = []

    async def main() -> None:
        sub = virtual_hub.subscribe("tiago/pose", lambda m: received.append(m))  # type: ignore[arg-type]
        async with _performer(virtual_hub, demo_bags, publish_topic="tiago/pose") as performer:
            outcome, _, feedback = await _move(virtual_hub, "tiago", "bathroom", "kitchen")
            assert isinstance(performer, BagNavigationPerformer)
            assert received and received[-1] is performer.pose
        sub.close()
        assert outcome.success
        assert len(received) == len(feedback)
        assert (received[0].x, received[0].y) == pytest.approx((1.0, 6.5))
        assert (received[-1].x, received[-1].y) == pytest.approx((0.0, 0.0))

    run(main(), virtual_hub.clock)


def _flat_knowledge() -> ProblemExpert:
    domain = parse_domain_files([REPO / "configs" / "pddl" / "flat_navigation.pddl"])
    knowledge = ProblemExpert(domain)
    knowledge.add_instance("tiago", "robot")
    knowledge.set_function("(= (robot_x tiago) 0)")
    return knowledge


def test_pose_goes_into_the_knowledge(virtual_hub: Hub, demo_bags: Path) -> None:
    knowledge = _flat_knowledge()
    seen: list[tuple[float, float | None, float | None]] = []
    knowledge.subscribe(
        lambda _c: seen.append(
            (
                virtual_hub.clock.now(),
                knowledge.get_function("robot_x", ("tiago",)),
                knowledge.get_function("robot_y", ("tiago",)),
            )
        )
    )
    binding = {"functions": {"x": "robot_x", "y": "robot_y"}, "period": 2.0}

    async def main() -> None:
        performer = _performer(virtual_hub, demo_bags, knowledge=binding)
        performer.context.knowledge = knowledge
        async with performer:
            outcome, _, _ = await _move(virtual_hub, "tiago", "kitchen", "livingroom")
        assert outcome.success

    run(main(), virtual_hub.clock)
    # one update (both functions in one transaction) every 2 s, and the final pose
    assert [round(t, 3) for t, _, _ in seen] == [0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0]
    assert seen[-1][1:] == pytest.approx((6.0, 0.5))
    assert seen[3][1] == pytest.approx(3.0, abs=0.2)  # at the door halfway


def test_unknown_knowledge_function_fails_the_action(virtual_hub: Hub, demo_bags: Path) -> None:
    knowledge = _flat_knowledge()
    binding = {"functions": {"x": "robot_x", "yaw": "heading"}}

    async def main() -> None:
        performer = _performer(virtual_hub, demo_bags, knowledge=binding)
        performer.context.knowledge = knowledge
        async with performer:
            outcome, _, _ = await _move(virtual_hub, "tiago", "kitchen", "livingroom")
        assert not outcome.success
        assert "cannot write the pose into the knowledge" in outcome.status
        assert "heading" in outcome.status
        # all-or-nothing: robot_x was not changed either
        assert knowledge.get_function("robot_x", ("tiago",)) == 0.0

    run(main(), virtual_hub.clock)
