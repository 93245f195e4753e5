"""The vehicle double's behaviour: an ArduCopter / ArduRover look-alike without sockets.

:class:`VehicleSim` takes decoded MAVLink messages in (:meth:`handle`), advances its
own simulated time (:meth:`step`) and queues MAVLink messages out. It copies the
parts of ArduPilot that a ground station has to cope with: a time base that starts
only when the first client connects, an EKF that needs a while before it has a
position estimate (arming refused with ``PreArm: Need Position Estimate`` until then),
telemetry sent only when asked for with MAV_CMD_SET_MESSAGE_INTERVAL, a copter that
disarms itself when left armed on the ground, LAND/RTL that end disarmed, a draining
battery, and faults a test can inject (failsafe, refused command, someone else's mode
change, STATUSTEXT error, dropped link).

The behaviour is spread by meaning over :mod:`.commands`, :mod:`.motion` and
:mod:`.telemetry`, on the state in :mod:`.state`. Everything runs on the caller's
thread; :mod:`.server` owns the thread and the socket and holds a lock around calls.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ..modes import mode_number
from .commands import SimCommands
from .motion import SimMotion
from .state import ML, SimParams

__all__ = ["SimParams", "VehicleSim"]


class VehicleSim(SimCommands, SimMotion):
    """State and behaviour of one simulated ArduPilot vehicle."""

    # ------------------------------------------------------------------ inputs
    def connect(self) -> None:
        """A client connected: start the clock (SITL waits for its first client)."""
        if not self.started:
            self.started = True
            self.statustext(ML.MAV_SEVERITY_INFO, f"ArduPilot {self._firmware()} double")
            self.statustext(ML.MAV_SEVERITY_INFO, "Calibrating barometer")

    # ------------------------------------------------------------------ faults
    def inject_failsafe(self, reason: str = "Battery") -> None:
        """Fault: a failsafe fires; copter goes to RTL (LAND on the ground), rover to HOLD."""
        self.failsafe = True
        self.statustext(ML.MAV_SEVERITY_CRITICAL, f"{reason} Failsafe")
        target = ("LAND" if self.landed else "RTL") if self.model == "copter" else "HOLD"
        self._enter_mode(mode_number(self.model, target))

    def inject_mode_change(self, name: str) -> None:
        """Fault: someone else (an RC switch, another GCS) changes the mode."""
        self._enter_mode(mode_number(self.model, name))

    def inject_wind(self, speed: float, from_deg: float) -> None:
        """Wind of ``speed`` m/s from ``from_deg`` (SIM_WIND_SPD / SIM_WIND_DIR)."""
        toward = math.radians(from_deg + 180.0)
        self.wind_ne = (speed * math.cos(toward), speed * math.sin(toward))

    def inject_link_drop(self, seconds: float) -> None:
        """Fault: nothing is sent or heard for ``seconds`` of simulated time."""
        self.link_down_until = self.time + seconds

    # ----------------------------------------------------------------- physics
    def step(self, dt: float) -> None:
        """Advance simulated time by ``dt`` seconds (nothing happens before a client)."""
        if not self.started or dt <= 0:
            return
        self.time += dt
        self._boot()
        if not self.ekf_ready and self.time >= self.p.ekf_delay:
            self.ekf_ready = True
            self.statustext(ML.MAV_SEVERITY_INFO, "EKF3 IMU0 is using GPS")
            self.statustext(ML.MAV_SEVERITY_INFO, "EKF3 IMU0 origin set")
        if self.armed:
            self._move(dt)
            moving = math.hypot(self.vn, self.ve) > 0.1 or abs(self.vd) > 0.1 or not self.landed
            drain = 100.0 / self.p.battery_capacity_s * (1.0 if moving else 0.1)
            self.battery = max(0.0, self.battery - drain * dt)
            self._check_battery()
            self._auto_disarm()
        self._stream()
        self.gcs.step()

    def _boot(self) -> None:
        # SITL's order whatever the delays: boot ends, RC input arrives, then the EKF
        # uses GPS (a short ekf_delay for fast tests brings the first two forward).
        if not self.booted and self.time >= min(self.p.boot_delay, self.p.ekf_delay):
            self.booted = True
            initial = "STABILIZE" if self.model == "copter" else "MANUAL"
            self._enter_mode(mode_number(self.model, initial))
            self.statustext(ML.MAV_SEVERITY_INFO, "ArduPilot Ready")
        if not self.rc_mode_read and self.time >= min(self.p.rc_mode_delay, self.p.ekf_delay):
            self.rc_mode_read = True
            self._enter_mode(mode_number(self.model, "MANUAL"))

    def _check_battery(self) -> None:
        if (
            self.p.battery_failsafe_pct > 0
            and not self.failsafe
            and self.battery <= self.p.battery_failsafe_pct
        ):
            self.inject_failsafe("Battery")

    def _auto_disarm(self) -> None:
        if self.model != "copter" or not self.armed or not self.landed or self.takeoff_alt:
            self.idle_since = None if not self.landed else self.idle_since
            return
        if self.idle_since is None:
            self.idle_since = self.time
        if self.time - self.idle_since >= self.p.disarm_delay:
            self._disarm("Disarming motors")

    def _firmware(self) -> str:
        return "ArduCopter V4.5" if self.model == "copter" else "ArduRover V4.5"

    def snapshot(self) -> Mapping[str, Any]:
        """A plain view of the state, for tests and the command line."""
        return {
            "time": self.time,
            "armed": self.armed,
            "mode": self.mode_name,
            "alt": self.alt,
            "north": self.north,
            "east": self.east,
            "landed": self.landed,
            "battery": self.battery,
            "ekf_ready": self.ekf_ready,
        }
