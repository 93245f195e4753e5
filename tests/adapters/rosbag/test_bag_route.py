"""Segments: which bag window serves which move, measured by arc length."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from plansys_bridge_adapters.rosbag.errors import BagError
from plansys_bridge_adapters.rosbag.reader import BagReader, PoseSample, read_poses
from plansys_bridge_adapters.rosbag.route import (
    PathProgress,
    Route,
    RouteError,
    Segment,
    SegmentProfile,
    distance,
    profile_segment,
)
from rosbag_testdata import HUSKY, real_bag

from plansys_bridge.errors import ConfigError


def _route(demo_bags: Path) -> Route:
    return Route.from_config(
        "kitchen_nav.segments.yaml",
        demo_bags,
        default_bag="kitchen_nav",
        default_topic="/odom",
    )


def test_segments_file_from_the_generator(demo_bags: Path) -> None:
    route = _route(demo_bags)
    assert len(route.segments) == 5
    seg = route.select("move", ("tiago", "kitchen", "livingroom"))
    assert seg.bag == (demo_bags / "kitchen_nav").resolve()
    assert (seg.start, seg.end) == (1.5, 13.5)
    assert route.select("move", ("r2d2", "bedroom", "bathroom")).name == "bedroom->bathroom"
    with pytest.raises(RouteError, match=r"\(move tiago kitchen bathroom\)"):
        route.select("move", ("tiago", "kitchen", "bathroom"))


def test_profile_of_a_generated_move(demo_bags: Path) -> None:
    route = _route(demo_bags)
    seg = route.select("move", ("tiago", "kitchen", "livingroom"))
    profile = route.profile(seg)
    assert profile.count == 121  # 12 s at 10 Hz, both ends included
    assert profile.duration == pytest.approx(12.0)
    assert profile.start == pytest.approx((0.0, 0.0, 0.0))
    assert profile.end == pytest.approx((6.0, 0.5, 0.0))
    # kitchen -> door (3, -0.5) -> livingroom (6, 0.5)
    assert profile.length == pytest.approx(
        math.dist((0, 0), (3, -0.5)) + math.dist((3, -0.5), (6, 0.5)), rel=1e-3
    )
    assert route.profile(seg) is profile


def test_progress_reaches_one_at_the_end_and_never_decreases(demo_bags: Path) -> None:
    seg = _route(demo_bags).select("move", ("tiago", "livingroom", "bedroom"))
    profile = profile_segment(seg)
    progress = PathProgress(profile)
    values = []
    with BagReader(seg.bag) as bag:
        start, stop = seg.window_ns(bag)
        for sample in bag.poses(seg.topic, start, stop):
            values.append(progress.update(sample))
    assert values[0] == 0.0
    assert values[-1] == pytest.approx(1.0)
    assert all(b >= a for a, b in itertools.pairwise(values))
    # the cosine speed profile: half the path at half the time
    assert values[len(values) // 2] == pytest.approx(0.5, abs=0.02)


def test_real_husky_segment() -> None:
    seg = Segment(bag=real_bag(HUSKY[0]), topic=HUSKY[1], start=100.0, end=160.0)
    profile = profile_segment(seg)
    assert 55.0 < profile.duration <= 60.0
    assert profile.count == pytest.approx(600, abs=5)  # 10 Hz odometry
    assert profile.length > 1.0
    first = next(read_poses(seg.bag, seg.topic))
    assert profile.first_ns - first.bag_time_ns >= 100 * 10**9 - 10**8


def test_empty_window_is_an_error(demo_bags: Path) -> None:
    seg = Segment(bag=demo_bags / "kitchen_nav", topic="/odom", start=500.0, end=510.0)
    with pytest.raises(BagError, match="holds no message"):
        profile_segment(seg)


@pytest.mark.parametrize(
    ("entries", "key"),
    [
        ([], "p.segments"),
        ([{"arguments": ["a"], "topic": "/odom"}], "p.segments[0].bag"),
        ([{"arguments": ["a"], "bag": "x"}], "p.segments[0].topic"),
        ([{"arguments": "a b", "bag": "x", "topic": "/o"}], "p.segments[0].arguments"),
        ([{"bag": "x", "topic": "/o", "start": 5, "end": 2}], "p.segments[0].end"),
        ([{"bag": "x", "topic": "/o", "start": -1}], "p.segments[0].start"),
        ([{"bag": "x", "topic": "/o", "stat": 1}], "p.segments[0].stat"),
        ("missing.yaml", "p.segments"),
    ],
)
def test_config_errors_name_the_key(tmp_path: Path, entries: object, key: str) -> None:
    with pytest.raises(ConfigError) as err:
        Route.from_config(entries, tmp_path, key="p.segments")
    assert err.value.key == key


def test_wildcards_and_action_filter() -> None:
    seg = Segment(bag=Path("b"), topic="/t", arguments=("", "a", "*"), action="move")
    assert seg.matches("move", ("r", "a", "b"))
    assert not seg.matches("move", ("r", "b", "b"))
    assert not seg.matches("fly", ("r", "a", "b"))
    assert not seg.matches("move", ("r", "a"))


def _sample(t: int, x: float, y: float) -> PoseSample:
    return PoseSample(
        t, t / 1e9, "map", x, y, 0.0, 0.0, 0.0, 0.0, 1.0, "geometry_msgs/msg/PoseStamped", b""
    )


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=2, max_size=40))
def test_progress_is_monotonic_and_ends_at_one(points: list[tuple[float, float]]) -> None:
    samples = [_sample(i * 10**8, x, y) for i, (x, y) in enumerate(points)]
    length = sum(distance(a, b) for a, b in itertools.pairwise(samples))
    profile = SegmentProfile(
        len(samples), samples[0].bag_time_ns, samples[-1].bag_time_ns, length, (0, 0, 0), (0, 0, 0)
    )
    progress = PathProgress(profile)
    values = [progress.update(s) for s in samples]
    assert all(0.0 <= v <= 1.0 for v in values)
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(values))
    assert values[-1] == pytest.approx(1.0)
