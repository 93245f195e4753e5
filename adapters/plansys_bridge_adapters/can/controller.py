"""Path following for a differential-drive base: pure pursuit with limits.

Pure logic, no I/O and no clock: :class:`PathFollower` gets the measured pose and
the time step, and returns the velocity set-point plus how far along the path the
base is. That keeps it testable on its own and lets the performer decide rates.

The follower drives a polyline (start, optional via points, goal). It steers with
pure pursuit towards a point ``lookahead`` metres further along the path, turns in
place first when the target is far off the nose, slows down so it can stop at the
goal with the configured deceleration, and rate-limits every command by the
acceleration limits so the base never sees a step. Arrival is by tolerance: the
position within ``goal_tolerance``, then (if the goal has a heading) the heading
within ``yaw_tolerance`` by turning in place.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

from .dbc import normalize_angle

Phase = Literal["turn", "track", "final_yaw", "stopping", "arrived"]


@dataclass(frozen=True)
class Pose2D:
    x: float
    y: float
    yaw: float = 0.0

    def distance_to(self, x: float, y: float) -> float:
        return math.hypot(x - self.x, y - self.y)


@dataclass(frozen=True)
class MotionLimits:
    """Velocity and acceleration limits of the set-points sent to the base."""

    max_linear: float = 0.5
    max_angular: float = 1.0
    max_linear_accel: float = 0.5
    max_angular_accel: float = 1.5

    def __post_init__(self) -> None:
        for name in ("max_linear", "max_angular", "max_linear_accel", "max_angular_accel"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")


@dataclass(frozen=True)
class ControllerConfig:
    lookahead: float = 0.4
    goal_tolerance: float = 0.05
    yaw_tolerance: float = 0.05
    rotate_in_place_angle: float = 0.8
    """Turn on the spot while the target is more than this far (rad) off the nose."""
    min_linear: float = 0.03
    """Creep speed so the last centimetres are covered despite the slow-down."""
    min_angular: float = 0.05
    """Creep turn rate for the last part of a turn."""
    heading_gain: float = 2.0
    limits: MotionLimits = field(default_factory=MotionLimits)

    def __post_init__(self) -> None:
        for name in ("lookahead", "goal_tolerance", "yaw_tolerance", "rotate_in_place_angle"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")


class Path:
    """A polyline in the odom frame, parametrised by arc length ``s``."""

    def __init__(self, points: Sequence[tuple[float, float]]) -> None:
        if not points:
            raise ValueError("a path needs at least one point")
        kept = [(float(points[0][0]), float(points[0][1]))]
        for x, y in points[1:]:
            if math.hypot(x - kept[-1][0], y - kept[-1][1]) > 1e-9:
                kept.append((float(x), float(y)))
        self.points: tuple[tuple[float, float], ...] = tuple(kept)
        starts = [0.0]
        for (x0, y0), (x1, y1) in itertools.pairwise(kept):
            starts.append(starts[-1] + math.hypot(x1 - x0, y1 - y0))
        self._starts = starts
        self.length = starts[-1]

    @property
    def goal(self) -> tuple[float, float]:
        return self.points[-1]

    def point_at(self, s: float) -> tuple[float, float]:
        """The point at arc length ``s`` (clamped to the path)."""
        if s <= 0 or len(self.points) == 1:
            return self.points[0]
        if s >= self.length:
            return self.points[-1]
        for i in range(len(self.points) - 1):
            if s <= self._starts[i + 1]:
                (x0, y0), (x1, y1) = self.points[i], self.points[i + 1]
                t = (s - self._starts[i]) / (self._starts[i + 1] - self._starts[i])
                return (x0 + t * (x1 - x0), y0 + t * (y1 - y0))
        return self.points[-1]

    def project(self, x: float, y: float, s_min: float = 0.0, s_max: float = math.inf) -> float:
        """Arc length of the closest path point within ``[s_min, s_max]``."""
        best_s, best_d = min(max(s_min, 0.0), self.length), math.inf
        for i in range(len(self.points) - 1):
            a, b = self._starts[i], self._starts[i + 1]
            if b < s_min or a > s_max:
                continue
            (x0, y0), (x1, y1) = self.points[i], self.points[i + 1]
            seg = b - a
            t = ((x - x0) * (x1 - x0) + (y - y0) * (y1 - y0)) / (seg * seg)
            s = min(max(a + max(0.0, min(1.0, t)) * seg, s_min), s_max)
            px, py = self.point_at(s)
            d = math.hypot(x - px, y - py)
            if d < best_d:
                best_s, best_d = s, d
        return best_s


@dataclass(frozen=True)
class ControlOutput:
    """One control step: the set-point to send and where the base is."""

    linear: float
    angular: float
    progress: float
    """Completion in [0, 1]: arc length covered (and final turn, if any)."""
    distance_to_goal: float
    phase: Phase

    @property
    def arrived(self) -> bool:
        return self.phase == "arrived"


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


def _approach(current: float, target: float, max_step: float) -> float:
    return current + _clamp(target - current, max_step)


class PathFollower:
    """Pure pursuit along a :class:`Path` to a goal with an optional final heading."""

    YAW_SHARE = 0.05
    """Share of the completion given to the final turn when the goal has a heading."""

    def __init__(
        self, path: Path, goal_yaw: float | None = None, config: ControllerConfig | None = None
    ) -> None:
        self.path = path
        self.goal_yaw = goal_yaw
        self.config = config or ControllerConfig()
        self._s = 0.0
        self._linear = 0.0
        self._angular = 0.0
        self._position_reached = path.length <= self.config.goal_tolerance
        self._initial_yaw_error: float | None = None
        self._yaw_reached = goal_yaw is None

    def reset_command(self, linear: float = 0.0, angular: float = 0.0) -> None:
        """Restart rate limiting from the base's measured twist."""
        self._linear, self._angular = linear, angular

    def update(self, pose: Pose2D, dt: float) -> ControlOutput:
        cfg, lim = self.config, self.config.limits
        gx, gy = self.path.goal
        distance = pose.distance_to(gx, gy)
        window = cfg.lookahead * 2 + lim.max_linear * max(dt, 0.0) + 0.5
        self._s = max(self._s, self.path.project(pose.x, pose.y, self._s - 0.05, self._s + window))
        if not self._position_reached and distance <= cfg.goal_tolerance:
            self._position_reached = True
        if self._position_reached:
            return self._final_turn(pose, distance, dt)
        remaining_path = self.path.length - self._s
        if remaining_path <= cfg.lookahead:
            tx, ty = gx, gy
            remaining = distance
        else:
            tx, ty = self.path.point_at(self._s + cfg.lookahead)
            remaining = remaining_path
        alpha = normalize_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.yaw)
        phase: Phase
        if abs(alpha) > cfg.rotate_in_place_angle:
            linear, angular, phase = 0.0, self._turn_rate(alpha), "turn"
        else:
            # Plan to stop half a tolerance short: the ramp-down after arrival covers the rest.
            stop_at = max(remaining - cfg.goal_tolerance / 2, 0.0)
            stop_speed = math.sqrt(2 * lim.max_linear_accel * stop_at)
            linear = max(min(lim.max_linear, stop_speed), cfg.min_linear)
            target_distance = max(math.hypot(tx - pose.x, ty - pose.y), 1e-6)
            curvature = 2 * math.sin(alpha) / target_distance
            angular = linear * curvature
            if abs(angular) > lim.max_angular:
                linear *= lim.max_angular / abs(angular)
                angular = math.copysign(lim.max_angular, angular)
            phase = "track"
        linear, angular = self._rate_limit(linear, angular, dt)
        progress = self._s / self.path.length if self.path.length > 0 else 1.0
        return ControlOutput(linear, angular, self._scaled(progress), distance, phase)

    def _turn_rate(self, error: float) -> float:
        """Turn rate towards ``error`` that can stop within half a tolerance of it."""
        cfg, lim = self.config, self.config.limits
        stop_at = max(abs(error) - cfg.yaw_tolerance / 2, 0.0)
        rate = min(
            lim.max_angular,
            cfg.heading_gain * abs(error),
            math.sqrt(2 * lim.max_angular_accel * stop_at),
        )
        return math.copysign(max(rate, cfg.min_angular), error)

    def _rate_limit(self, linear: float, angular: float, dt: float) -> tuple[float, float]:
        lim = self.config.limits
        step = max(dt, 0.0)
        self._linear = _approach(self._linear, linear, lim.max_linear_accel * step)
        self._angular = _approach(self._angular, angular, lim.max_angular_accel * step)
        return self._linear, self._angular

    def _scaled(self, path_progress: float) -> float:
        share = self.YAW_SHARE if self.goal_yaw is not None else 0.0
        return max(0.0, min(1.0, path_progress)) * (1.0 - share)

    def _final_turn(self, pose: Pose2D, distance: float, dt: float) -> ControlOutput:
        """At the goal: turn to the goal heading (if any), then ramp the command to zero."""
        share = 0.0
        target_angular = 0.0
        if self.goal_yaw is not None and not self._yaw_reached:
            error = normalize_angle(self.goal_yaw - pose.yaw)
            if self._initial_yaw_error is None:
                self._initial_yaw_error = max(abs(error), 1e-9)
            if abs(error) <= self.config.yaw_tolerance:
                self._yaw_reached = True
            else:
                target_angular = self._turn_rate(error)
                share = self.YAW_SHARE * min(abs(error) / self._initial_yaw_error, 1.0)
        linear, angular = self._rate_limit(0.0, target_angular, dt)
        if linear == 0.0 and angular == 0.0 and target_angular == 0.0:
            return ControlOutput(0.0, 0.0, 1.0, distance, "arrived")
        phase: Phase = "final_yaw" if target_angular else "stopping"
        return ControlOutput(linear, angular, min(1.0 - share, 0.999), distance, phase)
