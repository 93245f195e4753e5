"""The path follower on its own, closed-loop with the double's unicycle model (no bus)."""

from __future__ import annotations

import itertools
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from plansys_bridge_adapters.can.controller import (
    ControllerConfig,
    MotionLimits,
    Path,
    PathFollower,
    Pose2D,
)
from plansys_bridge_adapters.can.dbc import normalize_angle
from plansys_bridge_adapters.can.double import UnicycleModel

DT = 0.05


def drive(
    follower: PathFollower, model: UnicycleModel, max_time: float = 60.0
) -> tuple[list[float], list[tuple[float, float]], bool]:
    """Run the loop at 20 Hz; returns progress per step, commands, arrived."""
    progress: list[float] = []
    commands: list[tuple[float, float]] = []
    t = 0.0
    while t < max_time:
        out = follower.update(Pose2D(model.x, model.y, model.yaw), DT)
        progress.append(out.progress)
        commands.append((out.linear, out.angular))
        if out.arrived:
            return progress, commands, True
        for _ in range(5):
            model.step(DT / 5, out.linear, out.angular, 2.0, 6.0)
        t += DT
    return progress, commands, False


def test_path_arc_length_projection_and_points() -> None:
    path = Path([(0, 0), (3, 0), (3, 4), (3, 4)])
    assert path.length == pytest.approx(7.0)
    assert path.points == ((0, 0), (3, 0), (3, 4))
    assert path.point_at(1.5) == pytest.approx((1.5, 0.0))
    assert path.point_at(5.0) == pytest.approx((3.0, 2.0))
    assert path.point_at(-1) == (0, 0) and path.point_at(99) == (3, 4)
    assert path.project(1.0, 0.5) == pytest.approx(1.0)
    assert path.project(3.4, 2.0) == pytest.approx(5.0)
    # A window keeps the projection from jumping to a later part of the path.
    assert path.project(2.9, 0.1, 0.0, 2.0) == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("start", "goal", "yaw"),
    [
        ((0.0, 0.0, 0.0), (3.0, 1.5), None),
        ((0.0, 0.0, 0.0), (-2.0, 0.0), math.pi / 2),  # goal behind: turn first
        ((1.0, -1.0, 2.5), (1.0, -4.0), None),
        ((0.0, 0.0, 0.0), (0.0, 0.0), 1.0),  # already there: final turn only
    ],
)
def test_reaches_goal_within_tolerance(
    start: tuple[float, float, float], goal: tuple[float, float], yaw: float | None
) -> None:
    model = UnicycleModel(*start)
    config = ControllerConfig()
    follower = PathFollower(Path([start[:2], goal]), yaw, config)
    progress, _, arrived = drive(follower, model)
    assert arrived
    assert math.hypot(model.x - goal[0], model.y - goal[1]) <= config.goal_tolerance * 1.5
    if yaw is not None:
        assert abs(normalize_angle(model.yaw - yaw)) <= config.yaw_tolerance * 1.5
    assert progress[-1] == 1.0
    assert all(b >= a for a, b in itertools.pairwise(progress)), "progress went back"


def test_commands_respect_velocity_and_acceleration_limits() -> None:
    limits = MotionLimits(
        max_linear=0.4, max_angular=0.8, max_linear_accel=0.3, max_angular_accel=1.0
    )
    follower = PathFollower(Path([(0, 0), (2, 2), (4, 0)]), None, ControllerConfig(limits=limits))
    _, commands, arrived = drive(follower, UnicycleModel())
    assert arrived
    previous = (0.0, 0.0)
    for linear, angular in commands:
        assert abs(linear) <= limits.max_linear + 1e-9
        assert abs(angular) <= limits.max_angular + 1e-9
        assert abs(linear - previous[0]) <= limits.max_linear_accel * DT + 1e-9
        assert abs(angular - previous[1]) <= limits.max_angular_accel * DT + 1e-9
        previous = (linear, angular)


def test_follows_via_points() -> None:
    model = UnicycleModel()
    follower = PathFollower(Path([(0, 0), (2, 0), (2, 2)]), None)
    closest, progress_at_corner = math.inf, 0.0
    t = 0.0
    while t < 40:
        out = follower.update(Pose2D(model.x, model.y, model.yaw), DT)
        if out.arrived:
            break
        corner = math.hypot(model.x - 2, model.y)
        if corner < closest:
            closest, progress_at_corner = corner, out.progress
        for _ in range(5):
            model.step(DT / 5, out.linear, out.angular, 2.0, 6.0)
        t += DT
    assert out.arrived
    assert closest < 0.3  # it cut the corner, but went through it
    assert progress_at_corner == pytest.approx(0.5, abs=0.1)  # half the path, half the completion


def test_bad_limits_are_refused() -> None:
    with pytest.raises(ValueError, match="max_linear"):
        MotionLimits(max_linear=0)
    with pytest.raises(ValueError, match="goal_tolerance"):
        ControllerConfig(goal_tolerance=-1)


@settings(max_examples=25, deadline=None)
@given(
    st.floats(-4, 4),
    st.floats(-4, 4),
    st.floats(-math.pi, math.pi),
    st.one_of(st.none(), st.floats(-math.pi, math.pi)),
)
def test_reaches_any_goal(gx: float, gy: float, start_yaw: float, goal_yaw: float | None) -> None:
    model = UnicycleModel(0.0, 0.0, start_yaw)
    follower = PathFollower(Path([(0, 0), (gx, gy)]), goal_yaw)
    _, _, arrived = drive(follower, model, max_time=80)
    assert arrived
    assert math.hypot(model.x - gx, model.y - gy) <= 0.08
