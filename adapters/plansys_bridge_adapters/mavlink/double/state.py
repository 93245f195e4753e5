"""The simulated vehicle's settings and state, and the few moves every part of it makes.

:class:`SimState` holds what the double knows about itself (clock, arming, mode,
position, battery, faults waiting to fire) and how it speaks: every MAVLink message
it sends goes through :meth:`SimState._send` into an outbox the server drains. The
behaviour lives in the classes built on it: :mod:`.commands` (what a ground station
asks), :mod:`.motion` (how the vehicle moves), :mod:`.telemetry` (what it reports),
:mod:`.sim` (boot, faults and time).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..geo import GeoPoint, offset
from ..modes import Model, mode_name, mode_number
from .ground_station import GroundStationAnswers

ML = mavlink2


@dataclass
class SimParams:
    """Tunable vehicle behaviour, in simulated seconds, metres and percent."""

    model: Model = "copter"
    home: GeoPoint = field(default_factory=lambda: GeoPoint(-35.363261, 149.165230, 584.0))
    ekf_delay: float = 41.0
    """Seconds after the first client connects until the EKF uses GPS (SITL 4.6: ~41 s)."""
    boot_delay: float = 2.0
    """Seconds until "ArduPilot Ready" (SITL 4.6: ~2 s): the end of boot, when ArduPilot
    sets its initial mode over whatever mode a ground station set while it booted."""
    rc_mode_delay: float = 2.7
    """Rover: seconds until RC input arrives and the mode channel (RC 8, held at
    1800 by SITL) switches the rover to MANUAL, silently dropping an earlier mode."""
    disarm_delay: float = 10.0
    """DISARM_DELAY: a copter armed and idle on the ground disarms after this."""
    cruise_speed: float = 10.0
    climb_rate: float = 2.5
    descent_rate: float = 1.5
    land_speed: float = 1.0
    rtl_alt: float = 15.0
    wind_limit: float = 20.0
    """Strongest wind (m/s) a copter holds its course against at its largest lean
    angle; it drifts at the excess (SITL's quad holds 15 m/s and not 30)."""
    battery_capacity_s: float = 900.0
    """Seconds of flight/driving from 100 % to 0 % (idle drains a tenth as fast)."""
    battery_failsafe_pct: float = 0.0
    """Remaining % at which the battery failsafe fires (0 = off)."""
    position_modes_need_ekf: bool = False
    """Refuse GUIDED/LOITER/... without a position even when disarmed (ArduPilot
    allows any mode while disarmed and checks at arming; some firmware does not)."""
    system_id: int = 1
    component_id: int = 1


class SimState:
    """State of one simulated ArduPilot vehicle."""

    def __init__(self, params: SimParams) -> None:
        self.p = params
        self.model: Model = params.model
        self._outbox: list[bytes] = []
        self.mav = ML.MAVLink(
            _Collector(self._outbox), srcSystem=params.system_id, srcComponent=params.component_id
        )
        self.time = 0.0
        self.started = False
        self.booted = False
        self.rc_mode_read = self.model != "rover"
        self.armed = False
        # while booting: the copter reports STABILIZE, the rover INITIALISING
        self.mode = mode_number(
            self.model, "STABILIZE" if self.model == "copter" else "INITIALISING"
        )
        self.north = 0.0
        self.east = 0.0
        self.alt = 0.0  # metres above home
        self.vn = self.ve = self.vd = 0.0
        self.heading = 0.0
        self.battery = 100.0
        self.ekf_ready = False
        self.landed = True
        self.failsafe = False
        self.guided_target: GeoPoint | None = None
        self.takeoff_alt: float | None = None
        self.rtl_phase = ""
        self.idle_since: float | None = None
        self.intervals: dict[int, float] = {}
        self._last_sent: dict[int, float] = {}
        self._last_heartbeat = -math.inf
        self._refusals: dict[int, int] = {}
        self._lost_acks: set[int] = set()
        self.link_down_until = -math.inf
        self.wind_ne = (0.0, 0.0)
        """Where the wind blows an airborne copter, north and east in m/s."""
        self.commands_seen: list[int] = []
        self.gcs = GroundStationAnswers(self, self.model)
        """Parameters, streams and version, answered as ArduPilot does."""

    # ----------------------------------------------------------------- outputs
    def take_output(self) -> list[bytes]:
        """Packed MAVLink frames queued since the last call (nothing while the link is down)."""
        out, self._outbox[:] = list(self._outbox), []
        if self.link_down:
            return []
        return out

    @property
    def link_down(self) -> bool:
        return self.time < self.link_down_until

    def _send(self, msg: Any) -> None:
        self.mav.send(msg)

    def statustext(self, severity: int, text: str) -> None:
        self._send(self.mav.statustext_encode(severity, text[:50].encode()))

    # ---------------------------------------------------------------- position
    @property
    def position(self) -> GeoPoint:
        return offset(self.p.home, self.north, self.east, self.alt)

    @property
    def mode_name(self) -> str:
        return mode_name(self.model, self.mode)

    def _enter_mode(self, number: int) -> None:
        self.mode = number
        name = self.mode_name
        here = GeoPoint(self.position.lat, self.position.lon, self.alt)
        self.guided_target = None
        self.takeoff_alt = None
        self.rtl_phase = ""
        if name in ("GUIDED", "BRAKE", "LOITER", "HOLD", "POSHOLD") and not self.landed:
            self.guided_target = here if name == "GUIDED" else None
        if name == "RTL":
            self.rtl_phase = "climb" if self.model == "copter" else "return"

    def _disarm(self, text: str) -> None:
        self.armed = False
        self.idle_since = None
        self.guided_target = None
        self.takeoff_alt = None
        self.vn = self.ve = self.vd = 0.0
        self.statustext(ML.MAV_SEVERITY_INFO, text)


class _Collector:
    """File-like sink for pymavlink's encoder: keeps each packed frame."""

    def __init__(self, sink: list[bytes]) -> None:
        self._sink = sink

    def write(self, data: bytes) -> None:
        self._sink.append(bytes(data))
