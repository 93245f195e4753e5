"""``CanBasePerformer``: move actions of a plan, driven on a CAN mobile base.

A move action (``(move r2d2 dock kitchen)``) names a destination; the performer
looks it up in its locations, plans a polyline from the current odometry pose
through the location's ``via`` points, and runs :class:`PathFollower` at
``command_rate``, sending ``BASE_VelocityCmd`` with a fresh alive counter every
tick so the base's watchdog stays fed. Feedback is the fraction of the path
covered. The action succeeds when the base is within tolerance of the goal and
its measured twist confirms it stopped.

Every tick first asks the :class:`BaseMonitor` whether the base can still be
driven. A lost heartbeat, a fault bit, the e-stop, the watchdog bit, stale
odometry, a CAN error frame or a driver error ends the action: one zero-velocity
command goes out (the watchdog covers the case where it is not heard) and the
action finishes failed with that reason. A cancel sends zero velocity until the
twist confirms standstill, and engages the e-stop if it cannot.

The battery level of every status frame goes into the knowledge base when
``battery:`` is configured (a numeric fluent, plus an optional low-battery
predicate with hysteresis).
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.clock import VirtualClock
from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.hub.messages import PerformerState
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.entry import PerformerConfig

from .bus import BusSendError, CanBusClient
from .controller import Path, PathFollower, Pose2D
from .dbc import BaseStatus, EStopCommand, MobileBaseDbc, OdomPose, VelocityCommand
from .double import BaseDouble
from .monitor import BaseMonitor, Mark, Problem
from .replay import LogReplay
from .settings import (
    CanBaseSettings,
    CanSettings,
    Location,
    parse_motions,
    resolve,
    robot_name,
)

__all__ = ["CanBasePerformer"]

_LOG = logging.getLogger(__name__)


class _BaseFailure(Exception):
    """Internal: the base cannot be driven; the message is the action's status."""

    def __init__(self, message: str, transient: bool = False) -> None:
        super().__init__(message)
        self.transient = transient


class CanBasePerformer(ActionPerformer):
    """Drives one differential-drive base on a CAN bus (see the module docstring)."""

    Settings = CanSettings

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        settings: CanBaseSettings,
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
        self.settings = settings
        self.robot = settings.robot
        self.locations: dict[str, Location] = dict(settings.locations)
        self.dbc = MobileBaseDbc.load(settings.dbc)
        self.monitor = BaseMonitor(self.clock, settings.bus.describe())
        self.monitor.status_callbacks.append(self._battery_to_knowledge)
        self.monitor.pose_callbacks.append(self._record_pose)
        self.client = CanBusClient(settings.bus, self.dbc, self.monitor)
        self.double: BaseDouble | None = None
        """The simulated base started by ``simulate_base`` (None on a real bus)."""
        self.replay: LogReplay | None = None
        """The recorded log played in place of the base (``replay:``)."""
        self._counter = 0
        self._estop_counter = 0
        self._battery_written: float | None = None
        self._battery_low: bool | None = None
        self._knowledge_errors: set[str] = set()
        self._health_task: asyncio.Task[None] | None = None
        self._next_record = -math.inf
        self.base_problem: str | None = None
        """Why the base cannot be driven while idle (None: it can); shown as FAILURE."""

    # -- construction -----------------------------------------------------------

    @classmethod
    def parse_config(cls, config: Mapping[str, Any], *, key: str = "performer") -> PerformerConfig:
        """``actions`` of a base also says which argument is the destination
        (``{move: {robot: 0, destination: 2}}``); the common check sees the
        specialised arguments derived from it."""
        if not isinstance(config, Mapping):
            raise ConfigError("a performer entry must be a mapping", key=key)
        specs, _ = parse_motions(config.get("actions"), robot_name(config, key), f"{key}.actions")
        derived = {**config, "actions": {a: list(s) for a, s in specs.items()}}
        return replace(super().parse_config(derived, key=key), raw=config)

    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        actions = entry.raw.get("actions")
        settings = resolve(entry.settings, actions, context.base_dir, entry.key)
        return replace(entry, settings=settings)

    # -- lifecycle ----------------------------------------------------------------

    def connects_to(self) -> str:
        bus = self.settings.bus
        return f"CAN bus {bus.describe()} (from {bus.origin})"

    async def setup(self) -> None:
        if self.settings.simulate_base is not None:
            self.double = BaseDouble(
                self.clock, self.settings.bus, self.settings.simulate_base, self.dbc
            )
            await self.double.start()
        reader = self.settings.bus.reader
        if reader == "auto":
            # Threads do not live in virtual time: poll on the loop there.
            reader = "poll" if isinstance(self.clock, VirtualClock) else "notifier"
        try:
            await self.client.open(reader=reader)
            if self.settings.replay is not None:
                # after the client: a virtual bus hears only what is sent once it exists
                self.replay = LogReplay(self.clock, self.settings.bus.channel, self.settings.replay)
                await self.replay.start()
        except Exception:
            if self.double is not None:
                await self.double.stop()
                self.double = None
            if self.replay is not None:
                await self.replay.stop()
                self.replay = None
            raise
        self._health_task = asyncio.get_running_loop().create_task(
            self._watch_health(), name=f"{self.node_name}-base-health"
        )

    async def teardown(self) -> None:
        if self._health_task is not None:
            await cancel_and_wait(self._health_task)
            self._health_task = None
        if self.client.is_open:
            try:
                self._command(0.0, 0.0, enable=False)
            except _BaseFailure as exc:
                _LOG.warning("%s: could not send the final stop: %s", self.node_name, exc)
        await self.client.close()
        if self.double is not None:
            await self.double.stop()
            self.double = None
        if self.replay is not None:
            await self.replay.stop()
            self.replay = None

    # -- the action -------------------------------------------------------------------

    def bid(self, goal: ActionGoal) -> float | None:
        """Cost for best-bid auctions: straight-line distance to the destination."""
        location = self._destination(goal, strict=False)
        pose = self.monitor.pose
        if location is None or pose is None:
            return None
        return math.hypot(location.x - pose.x, location.y - pose.y)

    async def execute(self, goal: ActionGoal) -> str | None:
        location = self._destination(goal, strict=True)
        assert location is not None
        mark = self.monitor.mark()
        try:
            await self._wait_ready(mark)
            pose = self._pose()
            path = Path([(pose.x, pose.y), *location.via, (location.x, location.y)])
            follower = PathFollower(path, location.yaw, self.settings.controller)
            twist = self.monitor.twist
            if twist is not None:
                follower.reset_command(twist.linear, twist.angular)
            await self._follow(goal, location, follower, mark)
            await self._confirm_stop(mark, fail_on_problem=True)
        except _BaseFailure as exc:
            self._stop_quietly()
            raise ActionFailed(f"{goal.full_name}: {exc}") from exc
        final = self._pose()
        error = math.hypot(location.x - final.x, location.y - final.y)
        if error > self.settings.controller.goal_tolerance * 2:
            raise ActionFailed(
                f"{goal.full_name}: stopped {error:.3f} m from {location.name} "
                f"(tolerance {self.settings.controller.goal_tolerance:g} m)"
            )
        return (
            f"arrived at {location.name}: x={final.x:.3f} y={final.y:.3f} yaw={final.yaw:.3f} "
            f"(error {error:.3f} m)"
        )

    async def on_cancel(self, goal: ActionGoal) -> None:
        """Zero velocity until the twist confirms standstill; e-stop if it never does."""
        try:
            await self._confirm_stop(self.monitor.mark(), fail_on_problem=False)
        except _BaseFailure as exc:
            _LOG.error("%s: cancel of %s: %s", self.node_name, goal.full_name, exc)
            if self.settings.safety.estop_on_stop_failure:
                self.engage_estop()

    def engage_estop(self, engage: bool = True) -> None:
        """Send ``BASE_EStopCmd`` (engage or release)."""
        self._estop_counter = (self._estop_counter + 1) % 16
        try:
            self.client.send_frame(EStopCommand(engage, self._estop_counter))
        except BusSendError as exc:
            _LOG.error("%s: cannot send e-stop: %s", self.node_name, exc)
        else:
            _LOG.warning("%s: e-stop %s", self.node_name, "engaged" if engage else "released")

    # -- internals ---------------------------------------------------------------------

    def _destination(self, goal: ActionGoal, *, strict: bool) -> Location | None:
        motion = self.settings.motions.get(goal.action)
        if motion is None:
            if strict:
                raise ActionFailed(f"{goal.full_name}: {self.node_name} has no motion for it")
            return None
        if motion.robot_arg is not None and strict:
            args = goal.arguments
            robot = args[motion.robot_arg] if motion.robot_arg < len(args) else None
            if robot != self.robot:
                raise ActionFailed(
                    f"{goal.full_name}: argument {motion.robot_arg} is {robot!r}, "
                    f"this base is {self.robot!r}"
                )
        if motion.destination_arg >= len(goal.arguments):
            if strict:
                raise ActionFailed(
                    f"{goal.full_name}: no argument {motion.destination_arg} (the destination)"
                )
            return None
        name = goal.arguments[motion.destination_arg].lower()
        location = self.locations.get(name)
        if location is None and strict:
            known = ", ".join(sorted(self.locations))
            raise ActionFailed(f"{goal.full_name}: unknown location {name!r} (known: {known})")
        return location

    def _pose(self) -> Pose2D:
        pose = self.monitor.pose
        if pose is None:
            raise _BaseFailure("no odometry from the base", transient=True)
        return Pose2D(pose.x, pose.y, pose.yaw)

    def _problem(self, mark: Mark, *, ignore_watchdog: bool = False) -> Problem | None:
        """The monitor's verdict since ``mark`` under this base's safety settings."""
        safety = self.settings.safety
        return self.monitor.problem(
            self.clock.now(),
            mark,
            heartbeat_timeout=safety.heartbeat_timeout,
            odometry_timeout=safety.odometry_timeout,
            error_frame_limit=safety.error_frame_limit,
            ignore_watchdog=ignore_watchdog,
        )

    def _check(self, mark: Mark) -> None:
        problem = self._problem(mark)
        if problem is not None:
            raise _BaseFailure(problem.message, problem.transient)

    def _command(self, linear: float, angular: float, *, enable: bool = True) -> None:
        lim = self.settings.controller.limits
        self._counter = (self._counter + 1) % 16
        cmd = VelocityCommand(
            max(-lim.max_linear, min(lim.max_linear, linear)),
            max(-lim.max_angular, min(lim.max_angular, angular)),
            enable,
            self._counter,
        )
        try:
            self.client.send_frame(cmd)
        except BusSendError as exc:
            # While the interface is being reopened the failure may heal.
            raise _BaseFailure(str(exc), transient=self.client.reopening) from exc

    def _stop_quietly(self) -> None:
        try:
            self._command(0.0, 0.0, enable=False)
        except _BaseFailure as exc:
            _LOG.warning("%s: could not send zero velocity: %s", self.node_name, exc)

    async def _wait_ready(self, mark: Mark) -> None:
        """Wait for a status newer than the request, then check it and the odometry.

        Zero-velocity commands go out meanwhile: they clear a watchdog bit latched by
        an earlier stop. Transient problems (no data yet, that watchdog bit) may
        clear within ``startup_timeout``; a fault bit fails at once.
        """
        safety = self.settings.safety
        period = 1.0 / safety.command_rate
        start = self.clock.now()
        while True:
            timed_out = self.clock.now() - start >= safety.startup_timeout
            try:
                self._command(0.0, 0.0)
                status_time = self.monitor.status_time
                if (status_time is not None and status_time > start) or timed_out:
                    self._check(mark)
                    return
            except _BaseFailure as exc:
                if timed_out or not exc.transient:
                    raise
            await self.clock.sleep(period)

    async def _follow(
        self, goal: ActionGoal, location: Location, follower: PathFollower, mark: Mark
    ) -> None:
        safety = self.settings.safety
        period = 1.0 / safety.command_rate
        start = last = self.clock.now()
        next_feedback = start
        anchor = self._pose()
        anchor_time = start
        while True:
            await self.clock.sleep(period)
            now = self.clock.now()
            self._check(mark)
            pose = self._pose()
            out = follower.update(pose, now - last)
            last = now
            if out.arrived:
                self._command(0.0, 0.0)
                self.feedback(1.0, f"at {location.name}, stopping")
                return
            self._command(out.linear, out.angular)
            if now >= next_feedback:
                next_feedback = now + self.settings.feedback_period
                self.feedback(out.progress, f"{location.name}: {out.distance_to_goal:.2f} m to go")
            moved = (
                math.hypot(pose.x - anchor.x, pose.y - anchor.y) > 0.01
                or abs(math.remainder(pose.yaw - anchor.yaw, math.tau)) > 0.02
            )
            if moved:
                anchor, anchor_time = pose, now
            elif now - anchor_time > safety.stall_timeout:
                raise _BaseFailure(
                    f"base not moving although commanded for {safety.stall_timeout:g} s "
                    f"({out.distance_to_goal:.2f} m from {location.name})"
                )
            if safety.max_duration is not None and now - start > safety.max_duration:
                raise _BaseFailure(
                    f"did not reach {location.name} within {safety.max_duration:g} s "
                    f"({out.distance_to_goal:.2f} m to go)"
                )

    async def _confirm_stop(self, mark: Mark, *, fail_on_problem: bool) -> None:
        """Send zero velocity at the command rate until a twist shows standstill."""
        safety = self.settings.safety
        period = 1.0 / safety.command_rate
        start = self.clock.now()
        while True:
            self._command(0.0, 0.0)
            if fail_on_problem:
                self._check(mark)
            if self.monitor.is_stopped(safety.stopped_linear, safety.stopped_angular, start):
                return
            if self.clock.now() - start > safety.stop_timeout:
                twist = self.monitor.twist
                seen = (
                    "no odometry"
                    if twist is None
                    else (f"last twist v={twist.linear:.3f} m/s w={twist.angular:.3f} rad/s")
                )
                raise _BaseFailure(
                    f"base did not confirm standstill within {safety.stop_timeout:g} s ({seen})"
                )
            await self.clock.sleep(period)

    async def _watch_health(self) -> None:
        """While idle, report the base's state in the performer heartbeat.

        A faulted, e-stopped or silent base turns the performer FAILURE (PlanSys2's
        ActionPerformerStatus) until it recovers, so monitoring sees it before a plan
        tries to use it. Actions are still accepted and fail with the reason.
        """
        mark = self.monitor.mark()
        while True:
            await asyncio.sleep(self.heartbeat_period)
            problem = self._problem(mark, ignore_watchdog=True)
            mark = self.monitor.mark()
            if self.busy or not self.running:
                continue
            text = None if problem is None else problem.message
            if text != self.base_problem:
                if text is not None:
                    _LOG.warning("%s: base unavailable: %s", self.node_name, text)
                else:
                    _LOG.info("%s: base available again", self.node_name)
                self.base_problem = text
            wanted = PerformerState.READY if text is None else PerformerState.FAILURE
            if self.state != wanted:
                self.state = wanted
                self._publish_status()

    def _record_pose(self, pose: OdomPose) -> None:
        """Odometry into the mission bag (when one is recorded), every ``record_period``."""
        recorder = self.context.recorder
        record_pose = getattr(recorder, "record_pose", None)
        if record_pose is None or not getattr(recorder, "recording", True):
            return
        now = self.clock.now()
        if now < self._next_record:
            return
        self._next_record = now + self.settings.record_period
        try:
            record_pose(
                self.settings.record_topic, now, pose.x, pose.y, 0.0, pose.yaw, frame_id="odom"
            )
        except PlansysBridgeError as exc:
            # A full disk must not stop the robot; the bag just loses the poses.
            _LOG.error("%s: recording poses stopped: %s", self.node_name, exc)
            self._next_record = math.inf

    def _battery_to_knowledge(self, status: BaseStatus) -> None:
        battery = self.settings.battery
        knowledge = self.context.knowledge
        if battery is None or knowledge is None:
            return
        percent = status.battery_percent
        if battery.function is not None and (
            self._battery_written is None
            or abs(percent - self._battery_written) >= battery.min_change
        ):
            fact = f"(= ({battery.function} {self.robot}) {percent:g})"
            if self._tell(lambda: knowledge.set_function(fact), fact):
                self._battery_written = percent
        if battery.low_predicate is not None:
            fact = f"({battery.low_predicate} {self.robot})"
            was_low = self._battery_low
            if percent < battery.low_below:
                low = True
            elif was_low is None or percent >= battery.low_below + battery.hysteresis:
                low = False
            else:
                low = was_low
            if low == was_low:
                return
            if low:
                done = self._tell(lambda: knowledge.add_predicate(fact), fact)
            else:
                done = self._tell(
                    lambda: knowledge.exist_predicate(fact) and knowledge.remove_predicate(fact),
                    fact,
                )
            if done:
                self._battery_low = low

    def _tell(self, change: Callable[[], object], fact: str) -> bool:
        """Apply one knowledge change; a refusal is logged once per text, never raised."""
        try:
            change()
        except PlansysBridgeError as exc:
            text = str(exc)
            if text not in self._knowledge_errors:
                self._knowledge_errors.add(text)
                _LOG.error("%s: knowledge refused %s: %s", self.node_name, fact, text)
            return False
        return True
