"""``mavlink_replay``: a recorded flight (``.tlog``) as the vehicle, on the mission clock.

The log plays from the moment the performer starts, at its recorded pace (``rate``
> 1 faster), and every message goes through a :class:`MavlinkVehicle` exactly as if
it had come over a link: its telemetry cache, mode and arming state, STATUSTEXTs and
listeners, so sensing rules (``from: mavlink``) fire from the recorded values and a
plan reacts to them as it would in flight. On the virtual clock a 15-minute flight
replays in moments. Commands are not sent anywhere: what the vehicle did is what the
log says it did.

Each action of the plan is matched to a stretch of the recording (``segments``, in
seconds from the log's first message, by action text): it finishes when the replay
passes the end of the first stretch for that action not already over, reporting
progress through it. An action with no stretch left fails saying so, and so does one
whose stretch the log ends before (a cut-off recording). An action also fails when
the recorded vehicle shows a failsafe during it, found by the same supervision as a
live flight (:mod:`.supervision`): a failsafe STATUSTEXT or one of severity ERROR or
worse, a switch to RTL, LAND or SMART_RTL the action does not stand for (``rtl``,
``land``), or a HEARTBEAT system state CRITICAL or EMERGENCY::

    - kind: mavlink_replay
      name: copter1
      actions: {takeoff: [copter1], fly: [copter1], land: [copter1]}
      log: ../bags/logs/copter1.tlog
      rate: 1.0
      segments:
        - {action: (takeoff copter1 pad), start: 0, end: 10}
        - {action: (fly copter1 pad field), start: 10, end: 40}
        - {action: (land copter1 pad), start: 40, end: 86}
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Annotated

from pydantic import Field, field_validator, model_validator

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.errors import ConfigError
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.entry import PerformerConfig
from plansys_bridge.plugins import PluginSettings

from .errors import MavlinkError
from .modes import mode_table
from .tlog import TlogError, TlogSummary, read_tlog, summarize_tlog
from .vehicle import MavlinkVehicle

__all__ = ["MavlinkReplayPerformer", "MavlinkReplaySettings", "Segment", "SegmentSettings"]

log = logging.getLogger(__name__)

FAILSAFE_MODES = ("RTL", "LAND", "SMART_RTL")
"""Modes ArduPilot's failsafes switch to."""


@dataclass(frozen=True)
class Segment:
    action: str
    """Normalised action text: ``(fly copter1 pad field)``."""
    start: float
    end: float


def _norm(text: str) -> str:
    return "(" + " ".join(text.strip().strip("()").lower().split()) + ")"


class SegmentSettings(PluginSettings):
    """One stretch of the recording: the action it serves and where it lies."""

    action: str
    """An action such as ``(fly copter1 pad field)``."""
    start: Annotated[float, Field(ge=0)]
    """Seconds from the log's first message."""
    end: Annotated[float, Field(ge=0)]

    @field_validator("action")
    @classmethod
    def _is_an_action(cls, value: str) -> str:
        if not value.strip().startswith("(") or not value.strip().endswith(")"):
            raise ValueError(f"an action such as (fly copter1 pad field), got {value!r}")
        return value

    @model_validator(mode="after")
    def _ends_after_start(self) -> SegmentSettings:
        if self.end <= self.start:
            raise ValueError(f"end {self.end:g} is not after start {self.start:g}")
        return self


class MavlinkReplaySettings(PluginSettings):
    """The kind-specific keys of a ``kind: mavlink_replay`` entry (the module docs)."""

    log: Annotated[str, Field(min_length=1, pattern=r"\S")]
    """The recorded flight: a .tlog file (relative to the mission file)."""
    rate: float = Field(1.0, gt=0)
    """2.0 replays twice as fast as recorded."""
    segments: Annotated[list[SegmentSettings], Field(min_length=1)]


@dataclass(frozen=True)
class PreparedReplay:
    """The settings with the log found, read and checked, and the stretches fitted to it."""

    log: Path
    summary: TlogSummary
    segments: tuple[Segment, ...]
    rate: float


def prepare_replay(settings: MavlinkReplaySettings, base_dir: Path, key: str) -> PreparedReplay:
    """Read the log whole (every packet checked) and refuse a stretch past its end;
    errors name the key (and the log's file and byte offset)."""
    path = Path(settings.log).expanduser()
    path = path if path.is_absolute() else base_dir / path
    try:
        summary = summarize_tlog(path)
    except TlogError as exc:
        raise ConfigError(str(exc), key=f"{key}.log") from exc
    length = summary.last - summary.first
    for i, seg in enumerate(settings.segments):
        if seg.end > length + 1e-6:
            raise ConfigError(
                f"ends at {seg.end:g} s but the log lasts {length:.1f} s",
                key=f"{key}.segments[{i}].end",
            )
    segments = tuple(Segment(_norm(s.action), s.start, s.end) for s in settings.segments)
    return PreparedReplay(path, summary, segments, settings.rate)


class MavlinkReplayPerformer(ActionPerformer):
    """Serves a plan's actions from a recorded flight (see the module docs)."""

    Settings = MavlinkReplaySettings

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        settings: PreparedReplay,
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
        self.log_path = settings.log
        self.summary = settings.summary
        self.segments = settings.segments
        self.rate = settings.rate
        self.vehicle = MavlinkVehicle(f"tlog:{settings.log}")
        self.log_time = 0.0
        """Seconds into the recording replayed so far."""
        self.ended = False
        self._progress = asyncio.Event()
        self._replay_task: asyncio.Task[None] | None = None

    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        return replace(entry, settings=prepare_replay(entry.settings, context.base_dir, entry.key))

    def connects_to(self) -> str:
        return f"the recorded flight {self.log_path} ({self.summary.messages} messages)"

    async def setup(self) -> None:
        self._replay_task = asyncio.get_running_loop().create_task(
            self._play(), name=f"tlog-replay {self.node_name}"
        )

    async def teardown(self) -> None:
        if self._replay_task is not None:
            await cancel_and_wait(self._replay_task)
            self._replay_task = None

    async def _play(self) -> None:
        start = self.clock.now()
        first = self.summary.first
        try:
            for msg in read_tlog(self.log_path):
                offset = msg._timestamp - first
                wait = start + offset / self.rate - self.clock.now()
                if wait > 0:
                    await self.clock.sleep(wait)
                self.log_time = offset
                self.vehicle.receive(msg)
                self._tick()
        except TlogError as exc:  # the file changed since it was checked
            log.error("%s: %s", self.node_name, exc)
        self.ended = True
        self._tick()
        log.info("%s: the recorded flight ended at %.1f s", self.node_name, self.log_time)

    def _tick(self) -> None:
        self._progress.set()
        self._progress = asyncio.Event()

    def _segment(self, goal: ActionGoal) -> Segment | None:
        text = _norm(goal.full_name)
        return next((s for s in self.segments if s.action == text and s.end > self.log_time), None)

    def _expected_modes(self, goal: ActionGoal) -> frozenset[int]:
        """Every mode but the failsafe ones (RTL, LAND, SMART_RTL), unless the action is
        that mode (``rtl``, ``land``) or the vehicle was already in it when the action
        began: only a change *to* one the stretch does not stand for is a failsafe."""
        table = mode_table(self.vehicle.model or "copter")
        action = _norm(goal.full_name).strip("()").split()[0]
        refused = {
            table[name] for name in FAILSAFE_MODES if name in table and name.lower() != action
        }
        refused.discard(self.vehicle.telemetry.custom_mode)
        return frozenset(range(256)) - refused

    async def execute(self, goal: ActionGoal) -> str | None:
        segment = self._segment(goal)
        if segment is None:
            raise ActionFailed(
                f"the recorded flight has no stretch for {goal.full_name} after "
                f"{self.log_time:.1f} s"
            )
        vehicle = self.vehicle
        expected = vehicle.expected_modes = self._expected_modes(goal)
        try:
            return await vehicle.supervise(self._follow(goal, segment))
        except MavlinkError as exc:
            text = str(exc)
            mode = vehicle.telemetry.custom_mode
            if mode is not None and mode not in expected and vehicle.failsafe is None:
                text = (
                    f"the vehicle switched to {vehicle.mode_name_of(mode)}, which "
                    f"{goal.full_name} does not stand for"
                )
            raise ActionFailed(
                f"failsafe at {self.log_time:.1f} s of the recorded flight "
                f"{self.log_path.name}: {text}"
            ) from exc
        finally:
            vehicle.expected_modes = frozenset()

    async def _follow(self, goal: ActionGoal, segment: Segment) -> str:
        while self.log_time < segment.end:
            if self.ended:
                raise ActionFailed(
                    f"the recorded flight ends at {self.log_time:.1f} s, before "
                    f"{goal.full_name} ends at {segment.end:g} s"
                )
            done = (self.log_time - segment.start) / (segment.end - segment.start)
            self.feedback(min(1.0, max(0.0, done)), f"replaying {self.log_time:.1f} s")
            await self._progress.wait()
        return f"replayed {segment.start:g}-{segment.end:g} s of {self.log_path.name}"
