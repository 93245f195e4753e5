"""A navigation performer that drives by replaying recorded bags.

``BagNavigationPerformer`` executes ``move``-style actions by replaying the stretch
of a recorded bag that the configuration assigns to that move (see
:mod:`.route`). The replay follows the recorded timing on the project clock
(``rate`` > 1 plays faster), so a mission run offline keeps the durations and the
trajectories of the real robot; on the virtual clock a 15 s move costs no wall time.

While it runs, the performer:

* sends FEEDBACK with the completion along the recorded path (by arc length);
* writes the robot position into the knowledge base, if configured (``knowledge``:
  which action argument is the robot and which PDDL functions take ``x``, ``y``,
  ``z``, ``yaw``);
* hands every replayed message (as its ROS 2 type) to the mission recorder;
* publishes each replayed :class:`~.reader.PoseSample` on a hub topic, if
  ``publish_topic`` is set, for whatever else follows the robot (a monitor, a
  second robot's planner).

It finishes when the segment ends. A configuration that points at a missing bag,
topic or an empty window fails at start-up (``setup``), not in the middle of a run.

Mission file entry::

    - kind: rosbag
      name: tiago_nav
      actions: {move: [tiago]}
      bag: ../bags/kitchen_nav          # default for all segments
      topic: /odom
      segments: ../bags/kitchen_nav.segments.yaml   # or an inline list
      rate: 1.0                         # 2.0 replays twice as fast
      publish_rate: 10.0                # feedback / knowledge / recorder updates per s
      record_topic: /tiago/odom         # bag topic for the recorder (default /<name>/pose)
      publish_topic: tiago/pose         # also publish the replayed poses on the hub
      knowledge: {robot_argument: 0, functions: {x: robot_x, y: robot_y}}
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from plansys_bridge.errors import ConfigError, KnowledgeError
from plansys_bridge.pddl.model import FluentRef, FluentValue
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)

from ..checks import mapping
from .errors import BagError
from .reader import BagReader, PoseSample
from .route import PathProgress, Route, RouteError, Segment, SegmentProfile

POSE_FIELDS = ("x", "y", "z", "yaw")


@dataclass(frozen=True)
class KnowledgeBinding:
    """Which action argument names the robot, and which functions get its pose."""

    robot_argument: int
    functions: Mapping[str, str]
    """Pose field (``x``, ``y``, ``z``, ``yaw``) -> PDDL function name of one argument."""
    period: float = 1.0
    """Mission seconds between two knowledge updates (the last pose is always written)."""

    @classmethod
    def from_config(cls, value: Any, key: str) -> KnowledgeBinding | None:
        if value is None:
            return None
        value = mapping(
            value,
            key,
            ("robot_argument", "functions", "period"),
            "expected {robot_argument, functions, period}",
        )
        robot = value.get("robot_argument", 0)
        if isinstance(robot, bool) or not isinstance(robot, int) or robot < 0:
            raise ConfigError("expected an argument index >= 0", key=f"{key}.robot_argument")
        functions = value.get("functions")
        if not isinstance(functions, Mapping) or not functions:
            raise ConfigError(
                "expected a mapping of pose fields to PDDL functions, e.g. {x: robot_x}",
                key=f"{key}.functions",
            )
        for field_name, fn in functions.items():
            if field_name not in POSE_FIELDS:
                raise ConfigError(
                    f"unknown pose field {field_name!r} (known: {', '.join(POSE_FIELDS)})",
                    key=f"{key}.functions",
                )
            if not isinstance(fn, str) or not fn:
                raise ConfigError("expected a function name", key=f"{key}.functions.{field_name}")
        period = value.get("period", 1.0)
        if isinstance(period, bool) or not isinstance(period, int | float) or period <= 0:
            raise ConfigError("expected seconds > 0", key=f"{key}.period")
        return cls(
            robot,
            {str(k): str(v).lower() for k, v in functions.items()},
            float(period),
        )


class BagNavigationPerformer(ActionPerformer):
    """Executes moves by replaying recorded poses from ROS 1 / ROS 2 bags."""

    settings_keys: ClassVar[frozenset[str]] = frozenset(
        {
            "segments",
            "bag",
            "topic",
            "rate",
            "publish_rate",
            "record_topic",
            "publish_topic",
            "knowledge",
        }
    )

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        route: Route,
        rate: float = 1.0,
        publish_rate: float = 10.0,
        record_topic: str | None = None,
        publish_topic: str | None = None,
        knowledge: KnowledgeBinding | None = None,
        heartbeat_period: float = 1.0,
        commit_timeout: float = 2.0,
    ) -> None:
        super().__init__(
            context,
            node_name,
            actions,
            heartbeat_period=heartbeat_period,
            commit_timeout=commit_timeout,
        )
        if not rate > 0:
            raise ValueError(f"rate must be > 0, got {rate!r}")
        if not publish_rate > 0:
            raise ValueError(f"publish_rate must be > 0, got {publish_rate!r}")
        self.route = route
        self.rate = float(rate)
        self.publish_period = 1.0 / float(publish_rate)
        self.record_topic = record_topic or f"/{node_name}/pose"
        self.publish_topic = publish_topic
        self.knowledge_binding = knowledge
        self.pose: PoseSample | None = None
        """The last replayed pose (None before the first move)."""
        self.travelled = 0.0
        """Metres replayed so far over all moves."""

    # ------------------------------------------------------------------ config

    @classmethod
    def from_config(
        cls, config: Mapping[str, Any], context: PerformerContext, *, key: str = "performer"
    ) -> list[ActionPerformer]:
        parsed = cls.parse_config(config, key=key)
        s = parsed.settings
        if "segments" not in s:
            raise ConfigError(
                "missing: the bag segments that serve this performer's moves",
                key=f"{key}.segments",
            )
        for name in ("bag", "topic", "record_topic", "publish_topic"):
            if name in s and not isinstance(s[name], str):
                raise ConfigError(f"expected a string, got {s[name]!r}", key=f"{key}.{name}")
        route = Route.from_config(
            s["segments"],
            context.base_dir,
            key=f"{key}.segments",
            default_bag=s.get("bag"),
            default_topic=s.get("topic"),
        )
        rate = _positive(s.get("rate", 1.0), f"{key}.rate")
        publish_rate = _positive(s.get("publish_rate", 10.0), f"{key}.publish_rate")
        binding = KnowledgeBinding.from_config(s.get("knowledge"), f"{key}.knowledge")
        performer = cls(
            context,
            parsed.name,
            parsed.actions,
            route=route,
            rate=rate,
            publish_rate=publish_rate,
            record_topic=s.get("record_topic"),
            publish_topic=s.get("publish_topic"),
            knowledge=binding,
            heartbeat_period=parsed.heartbeat_period,
            commit_timeout=parsed.commit_timeout,
        )
        return [performer]

    # ------------------------------------------------------------------ hooks

    async def setup(self) -> None:
        """Measure every segment once: a missing bag/topic or an empty window fails here."""
        for segment in self.route.segments:
            self.route.profile(segment)

    def accepts(self, goal: ActionGoal) -> bool:
        return any(s.matches(goal.action, goal.arguments) for s in self.route.segments)

    def bid(self, goal: ActionGoal) -> float | None:
        """Cost = the recorded duration of the segment (shorter moves win best-bid)."""
        try:
            segment = self.route.select(goal.action, goal.arguments)
        except RouteError:
            return math.inf
        return self.route.profile(segment).duration / self.rate

    async def execute(self, goal: ActionGoal) -> str | None:
        try:
            segment = self.route.select(goal.action, goal.arguments)
            profile = self.route.profile(segment)
        except (RouteError, BagError) as exc:
            raise ActionFailed(str(exc)) from exc
        try:
            return await self._replay(goal, segment, profile)
        except BagError as exc:
            raise ActionFailed(f"{goal.full_name}: replay failed: {exc}") from exc

    # ------------------------------------------------------------------ replay

    async def _replay(self, goal: ActionGoal, segment: Segment, profile: SegmentProfile) -> str:
        clock = self.clock
        started = clock.now()
        progress = PathProgress(profile)
        next_publish = 0.0
        next_knowledge = 0.0
        pending: tuple[PoseSample, float, float] | None = None
        label = segment.name or segment.topic
        with BagReader(segment.bag) as bag:
            for sample in segment.poses(bag):
                completion = progress.update(sample)
                due = (sample.bag_time_ns - profile.first_ns) / 1e9 / self.rate
                if due < next_publish - 1e-9:
                    pending = (sample, completion, due)
                    continue
                pending = None
                await self._wait_until(started, due)
                self._publish_pose(goal, sample, completion, progress, label)
                # next slot on a fixed grid, so a jittery 10 Hz stream keeps its 10 Hz
                next_publish = (
                    math.floor(due / self.publish_period + 1e-9) + 1
                ) * self.publish_period
                if due >= next_knowledge:
                    self._update_knowledge(goal, sample)
                    next_knowledge = due + self._knowledge_period()
        if pending is not None:
            sample, completion, due = pending
            await self._wait_until(started, due)
            self._publish_pose(goal, sample, completion, progress, label)
        if self.pose is not None:
            self._update_knowledge(goal, self.pose)
        self.travelled += progress.travelled
        return (
            f"replayed {label}: {profile.count} poses, {progress.travelled:.2f} m "
            f"in {profile.duration / self.rate:.2f} s"
        )

    async def _wait_until(self, started: float, due: float) -> None:
        delay = due - (self.clock.now() - started)
        if delay > 0:
            await self.clock.sleep(delay)

    def _knowledge_period(self) -> float:
        return self.knowledge_binding.period if self.knowledge_binding else math.inf

    def _publish_pose(
        self,
        goal: ActionGoal,
        sample: PoseSample,
        completion: float,
        progress: PathProgress,
        label: str,
    ) -> None:
        self.pose = sample
        self.feedback(
            completion, f"{label}: {progress.travelled:.2f}/{progress.profile.length:.2f} m"
        )
        if self.publish_topic:
            self.hub.publish(self.publish_topic, sample)
        recorder = self.context.recorder
        record_cdr = getattr(recorder, "record_cdr", None)
        if record_cdr is not None and getattr(recorder, "recording", True):
            record_cdr(self.record_topic, sample.msgtype, sample.cdr, self.clock.now())

    def _update_knowledge(self, goal: ActionGoal, sample: PoseSample) -> None:
        binding = self.knowledge_binding
        knowledge = self.context.knowledge
        if binding is None or knowledge is None:
            return
        if binding.robot_argument >= len(goal.arguments):
            raise ActionFailed(
                f"{goal.full_name}: knowledge.robot_argument {binding.robot_argument} "
                f"is out of range for {len(goal.arguments)} argument(s)"
            )
        robot = goal.arguments[binding.robot_argument]
        values = {"x": sample.x, "y": sample.y, "z": sample.z, "yaw": sample.yaw}
        try:
            with knowledge.transaction():
                for field_name, function in binding.functions.items():
                    knowledge.set_function(
                        FluentValue(FluentRef(function, (robot,)), round(values[field_name], 6))
                    )
        except KnowledgeError as exc:
            raise ActionFailed(
                f"{goal.full_name}: cannot write the pose into the knowledge: {exc}"
            ) from exc


def _positive(value: Any, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ConfigError(f"must be a number > 0, got {value!r}", key=key)
    return float(value)
