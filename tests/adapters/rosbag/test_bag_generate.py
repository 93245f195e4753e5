"""The demo bag generator: deterministic, small, and what the committed bags/ holds."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from plansys_bridge_adapters.rosbag.generate import MOVES, main
from plansys_bridge_adapters.rosbag.reader import BagReader
from rosbags.highlevel import AnyReader


def _messages(path: Path) -> list[tuple[str, int, bytes]]:
    with AnyReader([path]) as reader:
        return [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("bags")
    assert main([str(out)]) == 0
    return out


def test_committed_bags_are_the_generator_output(generated: Path, demo_bags: Path) -> None:
    assert _messages(generated / "kitchen_nav") == _messages(demo_bags / "kitchen_nav")
    assert _messages(generated / "kitchen_nav_ros1.bag") == _messages(
        demo_bags / "kitchen_nav_ros1.bag"
    )
    assert (generated / "kitchen_nav.segments.yaml").read_text() == (
        demo_bags / "kitchen_nav.segments.yaml"
    ).read_text()


def test_demo_bags_are_small(generated: Path) -> None:
    sizes = [f.stat().st_size for f in generated.rglob("*") if f.is_file()]
    assert sum(sizes) < 1_000_000


def test_moves_take_ten_to_fifteen_seconds(generated: Path) -> None:
    segments = yaml.safe_load((generated / "kitchen_nav.segments.yaml").read_text())
    assert len(segments) == len(MOVES) >= 4
    for seg, move in zip(segments, MOVES, strict=True):
        assert seg["arguments"] == ["", move.origin, move.target]
        assert 10.0 <= seg["end"] - seg["start"] <= 15.0


def test_ros1_and_ros2_bags_hold_the_same_drive(generated: Path) -> None:
    with (
        BagReader(generated / "kitchen_nav") as ros2,
        BagReader(generated / "kitchen_nav_ros1.bag") as ros1,
    ):
        assert ros1.is_ros1 and not ros2.is_ros1
        odom = list(ros2.poses("/odom"))
        poses = list(ros1.poses("/robot_pose"))
    assert len(odom) == len(poses) == 741
    for a, b in zip(odom, poses, strict=True):
        assert a.bag_time_ns == b.bag_time_ns
        assert (a.x, a.y, a.yaw) == pytest.approx((b.x, b.y, b.yaw))
