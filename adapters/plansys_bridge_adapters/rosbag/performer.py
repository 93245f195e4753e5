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

It finishes when the segment ends. The entry's keys are the :class:`RosbagSettings`
model, checked when the mission loads, an inline ``segments`` list included; a
segments file is read when the performer is built, and a missing bag, topic or an
empty window fails at start-up (``setup``), not in the middle of a run.

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
from dataclasses import dataclass, replace
from typing import Annotated

from pydantic import Field, ValidationInfo, field_validator

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.pddl.model import FluentRef, FluentValue
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.entry import PerformerConfig
from plansys_bridge.plugins import PluginSettings

from .errors import BagError
from .reader import BagReader, PoseSample
from .route import (
    PathProgress,
    Route,
    RouteError,
    Segment,
    SegmentProfile,
    SegmentSpec,
    with_defaults,
)

POSE_FIELDS = ("x", "y", "z", "yaw")


class KnowledgeBinding(PluginSettings):
    """``knowledge:``: which action argument names the robot, and which functions get
    its pose."""

    robot_argument: int = Field(0, ge=0)
    functions: dict[str, Annotated[str, Field(min_length=1)]] = Field(min_length=1)
    """Pose field (``x``, ``y``, ``z``, ``yaw``) -> PDDL function name of one argument."""
    period: float = Field(1.0, gt=0.0)
    """Mission seconds between two knowledge updates (the last pose is always written)."""

    @field_validator("functions")
    @classmethod
    def _pose_fields(cls, value: dict[str, str]) -> dict[str, str]:
        for name in value:
            if name not in POSE_FIELDS:
                raise ValueError(f"unknown pose field {name!r} (known: {', '.join(POSE_FIELDS)})")
        return {name: function.lower() for name, function in value.items()}


class RosbagSettings(PluginSettings):
    """The kind-specific keys of a ``kind: rosbag`` performer entry."""

    bag: str | None = None
    """Default bag of the segments, relative to the mission file."""
    topic: str | None = None
    """Default pose topic of the segments."""
    segments: Annotated[list[SegmentSpec], Field(min_length=1)] | str
    """The bag stretches serving the moves: a YAML file of them (read when the
    performer is built), or the list, checked here so that a bad item is an error
    when the mission loads. After ``bag`` and ``topic``: the items take their
    defaults from them."""
    rate: float = Field(1.0, gt=0.0)
    publish_rate: float = Field(10.0, gt=0.0)
    """Feedback, knowledge and recorder updates per second."""
    record_topic: str | None = None
    publish_topic: str | None = None
    knowledge: KnowledgeBinding | None = None

    @field_validator("segments", mode="before")
    @classmethod
    def _file_or_list(cls, value: object, info: ValidationInfo) -> object:
        """One error for a value that is neither (pydantic would list both branches);
        the items of a list get the entry's default bag and topic."""
        if isinstance(value, str) and value.strip():
            return value
        if isinstance(value, list) and value:
            return with_defaults(value, info.data.get("bag"), info.data.get("topic"))
        raise ValueError(f"must be a segments file or a non-empty list of segments, got {value!r}")


@dataclass(frozen=True)
class BagReplay:
    """What the performer runs with: :class:`RosbagSettings` with the segments read."""

    route: Route
    rate: float = 1.0
    publish_rate: float = 10.0
    record_topic: str | None = None
    publish_topic: str | None = None
    knowledge: KnowledgeBinding | None = None


class BagNavigationPerformer(ActionPerformer):
    """Executes moves by replaying recorded poses from ROS 1 / ROS 2 bags.

    Built from a mission entry it gets :class:`BagReplay` as ``settings=``; code
    that has a :class:`Route` may pass ``route=`` alone for the default settings.
    """

    Settings = RosbagSettings

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        settings: BagReplay | None = None,
        route: Route | None = None,
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
        if settings is None:
            if route is None:
                raise TypeError("needs settings= (or route= for the default settings)")
            settings = BagReplay(route)
        elif route is not None:
            raise TypeError("give settings= or route=, not both")
        self.settings = settings
        self.route = settings.route
        self.rate = float(settings.rate)
        self.publish_period = 1.0 / float(settings.publish_rate)
        self.record_topic = settings.record_topic or f"/{node_name}/pose"
        self.publish_topic = settings.publish_topic
        self.knowledge_binding = settings.knowledge
        self.pose: PoseSample | None = None
        """The last replayed pose (None before the first move)."""
        self.travelled = 0.0
        """Metres replayed so far over all moves."""

    # ------------------------------------------------------------------ config

    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        """The route of the checked segments, or of the segments file next to the mission."""
        s: RosbagSettings = entry.settings
        if isinstance(s.segments, str):
            route = Route.from_config(
                s.segments,
                context.base_dir,
                key=f"{entry.key}.segments",
                default_bag=s.bag,
                default_topic=s.topic,
            )
        else:
            route = Route.from_specs(s.segments, context.base_dir)
        replay = BagReplay(
            route, s.rate, s.publish_rate, s.record_topic, s.publish_topic, s.knowledge
        )
        return replace(entry, settings=replay)

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
