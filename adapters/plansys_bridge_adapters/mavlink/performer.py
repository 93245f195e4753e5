"""``MavlinkPerformer``: plan actions performed by one ArduPilot copter or rover.

One performer drives one vehicle and serves several PDDL actions; ``commands`` says
what each action does on the vehicle, ``actions`` (PlanSys2's specialised
arguments) which calls it answers, so a fleet of vehicles each bid only for their
own PDDL object::

    - kind: mavlink
      name: uav1
      vehicle: uav1                       # the PDDL object this vehicle is
      double: {model: copter, speedup: 5} # or  url: tcp:127.0.0.1:5760
      locations: mavlink_locations.yaml
      actions: {takeoff: [], fly: [], land: []}
      commands:
        takeoff: {do: takeoff, vehicle_arg: 0, altitude: 10}
        fly:     {do: goto, vehicle_arg: 0, target_arg: 2}
        land:    {do: land, vehicle_arg: 0}

``do`` is one of ``takeoff``, ``goto``, ``land``, ``rtl``, ``hold``; without a
``commands`` entry an action named takeoff/land/rtl/hold does that and any other
action is a ``goto`` to its last argument. Each action runs supervised: a refused
command, a failsafe, a mode changed by someone else, a STATUSTEXT error or a lost
heartbeat ends it with FINISH(success=false) and a status naming the link and why.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Mapping, Sequence
from dataclasses import replace

from plansys_bridge.clock import VirtualClock
from plansys_bridge.errors import ConfigError
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.entry import PerformerConfig

from .double import VehicleDouble
from .errors import LinkError, MavlinkError, VehicleFault
from .geo import GeoPoint, distance_3d_m, distance_m
from .headway import Headway
from .safety import PUTS_DOWN, make_safe, make_safe_when_heard, safe_mode_for, stop_safely
from .settings import (
    Command,
    MavlinkEntry,
    MavlinkSettings,
    default_command,
    resolve,
    specialise,
)
from .telemetry import TelemetryPublisher
from .vehicle import LinkSettings, MavlinkVehicle

log = logging.getLogger(__name__)

RECOVERY_WAIT = 600.0
"""Seconds a performer keeps waiting, after a lost link, to make the vehicle safe."""


class MavlinkPerformer(ActionPerformer):
    """Performs take-off, go-to, land, RTL and hold on one ArduPilot vehicle."""

    Settings = MavlinkEntry

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        settings: MavlinkSettings,
        heartbeat_period: float = 1.0,
        commit_timeout: float = 2.0,
    ) -> None:
        if isinstance(context.clock, VirtualClock):
            raise ConfigError(
                "a MAVLink vehicle runs in real time: use a wall clock "
                "(clock: {kind: wall}), not the virtual clock",
                key="clock.kind",
            )
        if settings.url is None and settings.double is None:
            raise ConfigError("give the vehicle's url, or double: {model: ...}", key="url")
        super().__init__(
            context,
            node_name,
            actions,
            heartbeat_period=heartbeat_period,
            commit_timeout=commit_timeout,
        )
        self.settings = settings
        self.commands = {a: settings.commands.get(a) or default_command(a) for a in self.actions}
        self.double: VehicleDouble | None = None
        self.vehicle: MavlinkVehicle | None = None
        self.telemetry: TelemetryPublisher | None = None
        self._last_feedback = -1e9
        self._recovery: asyncio.Task[str | None] | None = None
        self._put_down = False
        """The safe mode (LAND, RTL) took the copter down while the plan has it in the
        air: the next flight takes off again, so a replan after a cancel still flies."""

    # -------------------------------------------------------------- lifecycle
    def connects_to(self) -> str:
        s = self.settings
        return f"MAVLink {s.url}" if s.url else f"the simulated {s.model or 'copter'} (double)"

    async def setup(self) -> None:
        s = self.settings
        url = s.url
        if s.double is not None:
            opts = dict(s.double)
            model = opts.pop("model", s.model or "copter")
            home = opts.pop("home", None)
            if isinstance(home, Mapping):
                opts["home"] = GeoPoint(
                    float(home["lat"]), float(home["lon"]), float(home.get("alt", 584.0))
                )
            self.double = VehicleDouble(model, **opts).start()
            url = self.double.url
        assert url is not None
        t = s.timeouts
        link = LinkSettings(
            connect_timeout=t.connect,
            heartbeat_timeout=t.heartbeat,
            command_timeout=t.command,
            telemetry_hz=s.telemetry_hz,
        )
        self.vehicle = MavlinkVehicle(url, link)
        try:
            await self.vehicle.connect()
        except MavlinkError:
            await self.teardown()
            raise
        if s.model is not None and self.vehicle.model != s.model:
            found = self.vehicle.model
            await self.teardown()
            raise ConfigError(f"{url}: expected a {s.model}, the vehicle is a {found}", key="model")
        if s.telemetry.enabled and self.context.knowledge is not None:
            self.telemetry = TelemetryPublisher(
                self.vehicle, self.context.knowledge, s.vehicle, s.telemetry
            )
            self.telemetry.start()

    async def teardown(self) -> None:
        await self._stop_recovery()
        if self.telemetry is not None:
            self.telemetry.stop()
            self.telemetry = None
        if self.vehicle is not None:
            await stop_safely(self.vehicle, self.settings.safe_mode, self.settings.disarm_on_stop)
            await self.vehicle.close()
        if self.double is not None:
            await asyncio.get_running_loop().run_in_executor(None, self.double.stop)
            self.double = None

    @property
    def url(self) -> str:
        return self.vehicle.url if self.vehicle is not None else str(self.settings.url)

    # -------------------------------------------------------------- auction
    def bid(self, goal: ActionGoal) -> float | None:
        """Cost for best-bid auctions: metres to the target of a go-to."""
        cmd = self.commands.get(goal.action)
        v = self.vehicle
        if cmd is None or cmd.do != "goto" or v is None or v.telemetry.position is None:
            return None
        try:
            target = self._target(goal, cmd, v.telemetry.home or v.telemetry.position)
        except ActionFailed:
            return None
        return distance_m(v.telemetry.position, target)

    # -------------------------------------------------------------- execution
    async def execute(self, goal: ActionGoal) -> str | None:
        cmd = self.commands[goal.action]
        self._last_feedback = -1e9
        self._note_safe(await self._stop_recovery())
        vehicle = await self._link()
        if vehicle.failsafe is not None and vehicle.telemetry.armed:
            raise ActionFailed(
                f"{vehicle.url}: the vehicle is in failsafe ({vehicle.failsafe!r}) and keeps "
                "control until it has landed"
            )
        vehicle.expected_modes = frozenset()
        vehicle.expect_armed = False
        run = getattr(self, f"_do_{cmd.do}")
        try:
            return str(await vehicle.supervise(run(vehicle, goal, cmd)))
        except MavlinkError as exc:
            if not (isinstance(exc, VehicleFault) and exc.took_over):
                mode = self._note_safe(await make_safe(vehicle, self.settings.safe_mode))
                if mode is None and isinstance(exc, LinkError):
                    self._recover_when_heard(vehicle)
            raise ActionFailed(str(exc)) from exc
        finally:
            vehicle.expected_modes = frozenset()
            vehicle.expect_armed = False

    async def on_cancel(self, goal: ActionGoal) -> None:
        """The safe mode (``safe_mode``: copter LAND by default, or RTL/BRAKE/...,
        LOITER if BRAKE is refused; rover HOLD, ...)."""
        v = self.vehicle
        if v is None or not v.connected:
            return
        mode = safe_mode_for(v.model, self.settings.safe_mode)
        modes = (mode, "LOITER") if mode == "BRAKE" else (mode,)
        if v.model == "copter" and not v.telemetry.armed:
            return  # on the ground: nothing moves
        for mode in modes:
            try:
                await v.set_mode(mode)
                self._note_safe(mode)
                return
            except MavlinkError as exc:
                log.warning("%s: cancel could not switch to %s: %s", v.url, mode, exc)

    def _recover_when_heard(self, vehicle: MavlinkVehicle) -> None:
        """The link was lost mid-action and the vehicle could not be told anything:
        make it safe as soon as it is heard again (until the next action or the end)."""
        self._recovery = asyncio.get_running_loop().create_task(
            make_safe_when_heard(vehicle, self.settings.safe_mode, RECOVERY_WAIT),
            name=f"{self.node_name}: safe mode when the link is back",
        )

    async def _stop_recovery(self) -> str | None:
        """Cancel the pending recovery; the safe mode it set, if it got to set one."""
        task, self._recovery = self._recovery, None
        if task is None:
            return None
        if not task.done():
            task.cancel()
        [mode] = await asyncio.gather(task, return_exceptions=True)
        return mode if isinstance(mode, str) else None

    def _note_safe(self, mode: str | None) -> str | None:
        """Remember a safe mode that lands a copter (see ``_put_down``); returns ``mode``."""
        if mode in PUTS_DOWN and self.vehicle is not None and self.vehicle.model == "copter":
            self._put_down = True
        return mode

    async def _link(self) -> MavlinkVehicle:
        v = self.vehicle
        if v is None:
            raise ActionFailed(f"{self.url}: performer not started")
        if not v.connected:
            await v.close()
            try:
                await v.connect()
            except MavlinkError as exc:
                raise ActionFailed(f"reconnect failed: {exc}") from exc
        return v

    def _progress(self, fraction: float, status: str) -> None:
        loop = asyncio.get_running_loop()
        now = loop.time()
        if fraction < 1.0 and now - self._last_feedback < self.settings.feedback_period:
            return
        self._last_feedback = now
        if self.goal is not None:
            self.feedback(fraction, status)

    def _require_copter(self, v: MavlinkVehicle, what: str) -> None:
        if v.model != "copter":
            raise ActionFailed(f"{v.url}: {what} needs a copter, this vehicle is a {v.model}")

    async def _arm_ready(self, v: MavlinkVehicle) -> None:
        """EKF ready, then GUIDED, then armed (retrying while arming checks fail).

        The mode is set only once the EKF reports a horizontal position: before
        that ArduPilot is still booting and drops a mode it accepted (the copter
        falls back to its initial mode at "ArduPilot Ready", the rover follows its
        RC mode channel once RC input arrives).
        """
        t = self.settings.timeouts
        if not v.telemetry.ekf_ready():
            self._progress(0.0, "waiting for the EKF to use GPS")
            await v.wait_ekf(t.ekf)
        await v.set_mode("GUIDED")
        if not v.telemetry.armed:
            self._progress(0.0, "arming")
            await v.arm(t.arm)
        v.expect_armed = True

    async def _do_takeoff(self, v: MavlinkVehicle, goal: ActionGoal, cmd: Command) -> str:
        self._require_copter(v, "take-off")
        alt = cmd.altitude if cmd.altitude is not None else self.settings.cruise_altitude
        pos = await v.wait_position(self.settings.timeouts.connect)
        if v.telemetry.armed and pos.alt > self.settings.altitude_tolerance:
            v.expect_armed = True
            return await self._fly(v, GeoPoint(pos.lat, pos.lon, alt), "take-off altitude")
        await self._arm_ready(v)
        await v.takeoff(alt)  # promptly: an idle armed copter disarms after DISARM_DELAY
        tol = self.settings.altitude_tolerance
        deadline = asyncio.get_running_loop().time() + self.settings.timeouts.action
        while True:
            here = v.telemetry.position or pos
            self._progress(max(0.0, min(1.0, here.alt / alt)), f"climbing {here.alt:.1f}/{alt:g} m")
            if here.alt >= alt - tol:
                return f"airborne at {here.alt:.1f} m"
            self._check_deadline(v, deadline, "take-off")
            await v.wait_message(0.2)

    async def _do_goto(self, v: MavlinkVehicle, goal: ActionGoal, cmd: Command) -> str:
        home = await v.wait_home(self.settings.timeouts.ekf) if self._needs_home() else None
        pos = await v.wait_position(self.settings.timeouts.connect)
        target = self._target(goal, cmd, home or pos)
        name = goal.arguments[cmd.target_arg]
        if v.model == "copter":
            on_ground = not v.telemetry.armed or pos.alt < self.settings.altitude_tolerance
            if on_ground and (cmd.takeoff or self._put_down):
                alt = cmd.altitude if cmd.altitude is not None else self.settings.cruise_altitude
                await self._do_takeoff(v, goal, Command("takeoff", altitude=alt))
                on_ground = False
            self._put_down = False
            if on_ground:
                raise ActionFailed(
                    f"{v.url}: the copter is on the ground; take off before flying to {name}"
                )
            await v.set_mode("GUIDED")
            v.expect_armed = True
        else:
            await self._arm_ready(v)
        return await self._fly(v, target, name)

    async def _fly(self, v: MavlinkVehicle, target: GeoPoint, name: str) -> str:
        """Send position targets until within the arrival radius; feedback = leg done."""
        s = self.settings
        copter = v.model == "copter"
        start = v.telemetry.position or target
        leg = distance_3d_m(start, target) if copter else distance_m(start, target)
        loop = asyncio.get_running_loop()
        deadline = loop.time() + s.timeouts.action
        last_send = -1e9
        guided = v.mode_number("GUIDED")
        headway = Headway(s.timeouts.stall)
        while True:
            now = loop.time()
            if now - last_send >= s.resend_period:
                if v.telemetry.custom_mode != guided:
                    # ArduPilot ignores targets outside GUIDED, without an answer
                    raise ActionFailed(f"{v.url}: the vehicle left GUIDED (now {v.mode})")
                v.send_position_target(target)
                last_send = now
            here = v.telemetry.position or start
            horizontal = distance_m(here, target)
            remaining = distance_3d_m(here, target) if copter else horizontal
            done = 1.0 - remaining / leg if leg > 1e-6 else 1.0
            self._progress(max(0.0, min(1.0, done)), f"{remaining:.1f} m to {name}")
            if horizontal <= s.arrival_radius and (
                not copter or abs(here.alt - target.alt) <= s.altitude_tolerance
            ):
                return f"reached {name} ({horizontal:.1f} m off)"
            if not headway.update(remaining, v.telemetry.position_time):
                raise VehicleFault(v.url, headway.describe(name, remaining, v.telemetry.velocity))
            self._check_deadline(v, deadline, f"going to {name}")
            await v.wait_message(0.2)

    async def _do_land(self, v: MavlinkVehicle, goal: ActionGoal, cmd: Command) -> str:
        self._put_down = False
        if v.model != "copter":
            await v.set_mode("HOLD")
            if v.telemetry.armed:
                await v.disarm()
            return "stopped and disarmed"
        if not v.telemetry.armed:
            return "already on the ground, disarmed"
        await v.set_mode("LAND")
        return await self._wait_landed(v, "landing")

    async def _wait_landed(self, v: MavlinkVehicle, what: str) -> str:
        start_alt = max((v.telemetry.position.alt if v.telemetry.position else 0.0), 0.1)
        deadline = asyncio.get_running_loop().time() + self.settings.timeouts.action
        while v.telemetry.armed:
            alt = v.telemetry.position.alt if v.telemetry.position else start_alt
            self._progress(max(0.0, min(0.99, 1.0 - alt / start_alt)), f"{what}: {alt:.1f} m")
            self._check_deadline(v, deadline, what)
            await v.wait_message(0.2)
        return "landed and disarmed"

    async def _do_rtl(self, v: MavlinkVehicle, goal: ActionGoal, cmd: Command) -> str:
        if not v.telemetry.armed:
            return "already disarmed"
        home = await v.wait_home(self.settings.timeouts.ekf)
        await v.set_mode("RTL")
        if v.model == "copter":
            return await self._wait_landed(v, "returning to launch")
        start = v.telemetry.position or home
        leg = max(distance_m(start, home), 1e-6)
        deadline = asyncio.get_running_loop().time() + self.settings.timeouts.action
        while True:
            here = v.telemetry.position or start
            d = distance_m(here, home)
            self._progress(max(0.0, min(1.0, 1.0 - d / leg)), f"{d:.1f} m to home")
            if d <= self.settings.arrival_radius:
                await v.set_mode("HOLD")
                return "back at home, holding"
            self._check_deadline(v, deadline, "return to launch")
            await v.wait_message(0.2)

    async def _do_hold(self, v: MavlinkVehicle, goal: ActionGoal, cmd: Command) -> str:
        mode = "LOITER" if v.model == "copter" else "HOLD"
        if v.model == "copter" and not v.telemetry.armed:
            return "on the ground"
        await v.set_mode(mode)
        if cmd.seconds:
            await self.clock.sleep(cmd.seconds)
        return f"holding in {mode}"

    def _check_deadline(self, v: MavlinkVehicle, deadline: float, what: str) -> None:
        if asyncio.get_running_loop().time() > deadline:
            raise ActionFailed(
                f"{v.url}: {what} took longer than {self.settings.timeouts.action:g} s"
            )

    def _needs_home(self) -> bool:
        locs = self.settings.locations
        return locs is None or locs.origin is None

    def _target(self, goal: ActionGoal, cmd: Command, home: GeoPoint) -> GeoPoint:
        locs = self.settings.locations
        if locs is None:
            raise ActionFailed(f"{self.url}: no locations configured for {goal.full_name}")
        try:
            name = goal.arguments[cmd.target_arg]
        except IndexError:
            raise ActionFailed(
                f"{goal.full_name} has no argument {cmd.target_arg} "
                f"(the target_arg of {goal.action})"
            ) from None
        try:
            place = locs.get(name)
        except KeyError as exc:
            raise ActionFailed(str(exc.args[0])) from None
        default = self.settings.cruise_altitude if locs.default_alt is None else locs.default_alt
        point = place.resolve(home, locs.origin, default)
        if self.vehicle is not None and self.vehicle.model == "rover":
            point = GeoPoint(point.lat, point.lon, 0.0)
        return point

    # -------------------------------------------------------------- config
    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        """The vehicle named, the locations loaded, the vehicle's PDDL object put at
        each command's ``vehicle_arg``."""
        settings = resolve(entry.settings, entry.name, context.base_dir, entry.key)
        actions = specialise(entry.actions, settings, entry.key)
        return replace(entry, settings=settings, actions=actions)
