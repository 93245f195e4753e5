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

Everything here runs on the caller's thread; :mod:`.server` owns the thread and the
socket and holds a lock around calls.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from ..geo import GeoPoint, distance_m, north_east_m, offset
from ..modes import (
    MAV_AUTOPILOT_ARDUPILOTMEGA,
    MAV_TYPE_GROUND_ROVER,
    MAV_TYPE_QUADROTOR,
    Model,
    mode_name,
    mode_number,
    mode_table,
)

ML = mavlink2

# EKF_STATUS_REPORT flags as SITL reports them before and after GPS is used.
EKF_FLAGS_BOOTING = ML.EKF_UNINITIALIZED
EKF_FLAGS_NO_GPS = (
    ML.EKF_ATTITUDE
    | ML.EKF_VELOCITY_HORIZ
    | ML.EKF_VELOCITY_VERT
    | ML.EKF_POS_VERT_ABS
    | ML.EKF_CONST_POS_MODE
)
EKF_FLAGS_GPS = (
    ML.EKF_ATTITUDE
    | ML.EKF_VELOCITY_HORIZ
    | ML.EKF_VELOCITY_VERT
    | ML.EKF_POS_HORIZ_REL
    | ML.EKF_POS_HORIZ_ABS
    | ML.EKF_POS_VERT_ABS
    | ML.EKF_PRED_POS_HORIZ_REL
    | ML.EKF_PRED_POS_HORIZ_ABS
)

# Telemetry a client may ask for, with ArduPilot's message ids.
STREAMABLE = frozenset(
    {
        ML.MAVLINK_MSG_ID_HEARTBEAT,
        ML.MAVLINK_MSG_ID_SYS_STATUS,
        ML.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
        ML.MAVLINK_MSG_ID_EKF_STATUS_REPORT,
        ML.MAVLINK_MSG_ID_HOME_POSITION,
        ML.MAVLINK_MSG_ID_BATTERY_STATUS,
        ML.MAVLINK_MSG_ID_VFR_HUD,
    }
)

# Copter modes that may be armed in (ArduCopter refuses e.g. RTL and LAND).
COPTER_ARMABLE = frozenset(
    {
        "STABILIZE",
        "ACRO",
        "ALT_HOLD",
        "GUIDED",
        "LOITER",
        "POSHOLD",
        "AUTO",
        "SPORT",
        "DRIFT",
        "BRAKE",
    }
)
# Modes that need a position estimate to be entered while armed (ArduPilot's requires_GPS).
NEEDS_POSITION = frozenset(
    {"GUIDED", "LOITER", "RTL", "AUTO", "POSHOLD", "BRAKE", "CIRCLE", "SMART_RTL", "HOLD"}
)
FORCE_DISARM_MAGIC = 21196


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
    battery_capacity_s: float = 900.0
    """Seconds of flight/driving from 100 % to 0 % (idle drains a tenth as fast)."""
    battery_failsafe_pct: float = 0.0
    """Remaining % at which the battery failsafe fires (0 = off)."""
    position_modes_need_ekf: bool = False
    """Refuse GUIDED/LOITER/... without a position even when disarmed (ArduPilot
    allows any mode while disarmed and checks at arming; some firmware does not)."""
    system_id: int = 1
    component_id: int = 1


class VehicleSim:
    """State and behaviour of one simulated ArduPilot vehicle."""

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
        self.commands_seen: list[int] = []

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

    # ------------------------------------------------------------------ inputs
    def connect(self) -> None:
        """A client connected: start the clock (SITL waits for its first client)."""
        if not self.started:
            self.started = True
            self.statustext(ML.MAV_SEVERITY_INFO, f"ArduPilot {self._firmware()} double")
            self.statustext(ML.MAV_SEVERITY_INFO, "Calibrating barometer")

    def handle(self, msg: Any) -> None:
        """React to one decoded message from the ground station."""
        if self.link_down:
            return
        kind = msg.get_type()
        if kind == "COMMAND_LONG":
            if msg.target_system in (0, self.p.system_id):
                params = (
                    msg.param1,
                    msg.param2,
                    msg.param3,
                    msg.param4,
                    msg.param5,
                    msg.param6,
                    msg.param7,
                )
                self._command(msg.command, params)
        elif kind == "COMMAND_INT":
            if msg.target_system in (0, self.p.system_id):
                params = (
                    msg.param1,
                    msg.param2,
                    msg.param3,
                    msg.param4,
                    msg.x / 1e7,
                    msg.y / 1e7,
                    msg.z,
                )
                self._command(msg.command, params, frame=msg.frame)
        elif kind == "SET_MODE":
            if msg.target_system in (0, self.p.system_id):
                result = self._set_mode(int(msg.custom_mode))
                self._ack(ML.MAVLINK_MSG_ID_SET_MODE, result)
        elif kind == "SET_POSITION_TARGET_GLOBAL_INT" and msg.target_system in (
            0,
            self.p.system_id,
        ):
            self._position_target(msg)

    # ---------------------------------------------------------------- commands
    def refuse_next(self, command: int, result: int = ML.MAV_RESULT_DENIED) -> None:
        """Fault: answer the next ``command`` with ``result`` instead of obeying it."""
        self._refusals[command] = result

    def lose_next_ack(self, command: int) -> None:
        """Fault: obey the next ``command`` but lose its COMMAND_ACK, as a radio can."""
        self._lost_acks.add(command)

    def _ack(self, command: int, result: int) -> None:
        if command in self._lost_acks:
            self._lost_acks.discard(command)
            return
        self._send(self.mav.command_ack_encode(command, result))

    def _command(self, command: int, p: tuple[float, ...], frame: int = 0) -> None:
        self.commands_seen.append(command)
        if command in self._refusals:
            self._ack(command, self._refusals.pop(command))
            return
        try:
            self._obey(command, p)
        except (ValueError, OverflowError):
            # NaN or infinity where a mode, message id or flag is needed: refused,
            # never the end of the double's thread.
            self._ack(command, ML.MAV_RESULT_DENIED)

    def _obey(self, command: int, p: tuple[float, ...]) -> None:
        if command == ML.MAV_CMD_SET_MESSAGE_INTERVAL:
            self._ack(command, self._set_interval(int(p[0]), p[1]))
        elif command == ML.MAV_CMD_REQUEST_MESSAGE:
            sent = self._send_telemetry(int(p[0]))
            self._ack(command, ML.MAV_RESULT_ACCEPTED if sent else ML.MAV_RESULT_FAILED)
        elif command == ML.MAV_CMD_DO_SET_MODE:
            self._ack(command, self._set_mode(int(p[1])))
        elif command == ML.MAV_CMD_COMPONENT_ARM_DISARM:
            self._ack(command, self._arm(p[0] > 0.5, int(p[1]) == FORCE_DISARM_MAGIC))
        elif command == ML.MAV_CMD_NAV_TAKEOFF:
            self._ack(command, self._takeoff(p[6]))
        elif command == ML.MAV_CMD_NAV_LAND:
            self._ack(
                command,
                self._set_mode(mode_number(self.model, "LAND"))
                if self.model == "copter"
                else ML.MAV_RESULT_UNSUPPORTED,
            )
        elif command == ML.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            self._ack(command, self._set_mode(mode_number(self.model, "RTL")))
        elif command == ML.MAV_CMD_DO_REPOSITION:
            self._ack(command, self._reposition(p))
        else:
            self._ack(command, ML.MAV_RESULT_UNSUPPORTED)

    def _set_interval(self, msg_id: int, interval_us: float) -> int:
        if msg_id not in STREAMABLE:
            return ML.MAV_RESULT_FAILED
        if interval_us < 0:
            self.intervals.pop(msg_id, None)
        else:
            default = 1.0 if msg_id == ML.MAVLINK_MSG_ID_HEARTBEAT else 0.25
            self.intervals[msg_id] = interval_us / 1e6 if interval_us > 0 else default
        return ML.MAV_RESULT_ACCEPTED

    def _set_mode(self, number: int, *, by_pilot: bool = False) -> int:
        if number not in mode_table(self.model).values():
            return ML.MAV_RESULT_UNSUPPORTED
        name = mode_name(self.model, number)
        checked = self.armed or self.p.position_modes_need_ekf
        if checked and not self.ekf_ready and name in NEEDS_POSITION and not by_pilot:
            text = f"Mode change failed: {name} requires position"
            self.statustext(ML.MAV_SEVERITY_WARNING, text)
            return ML.MAV_RESULT_FAILED
        self._enter_mode(number)
        return ML.MAV_RESULT_ACCEPTED

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

    def _arm(self, arm: bool, force: bool) -> int:
        if not arm:
            if not self.armed:
                return ML.MAV_RESULT_FAILED  # AP_Arming::disarm: "already disarmed" is false
            if self.model == "copter" and not self.landed and not force:
                self.statustext(ML.MAV_SEVERITY_CRITICAL, "Disarm: not landed")
                return ML.MAV_RESULT_FAILED
            self._disarm("Disarming motors")
            return ML.MAV_RESULT_ACCEPTED
        if self.armed:
            return ML.MAV_RESULT_ACCEPTED
        if not self.ekf_ready:
            self.statustext(ML.MAV_SEVERITY_CRITICAL, "Arm: Need Position Estimate")
            return ML.MAV_RESULT_FAILED
        if self.model == "copter" and self.mode_name not in COPTER_ARMABLE:
            self.statustext(ML.MAV_SEVERITY_CRITICAL, "Arm: Mode not armable")
            return ML.MAV_RESULT_FAILED
        if self.battery <= max(self.p.battery_failsafe_pct, 0.0) + 1e-9 and self.battery < 100:
            self.statustext(ML.MAV_SEVERITY_CRITICAL, "PreArm: Battery 1 below minimum capacity")
            return ML.MAV_RESULT_FAILED
        self.armed = True
        self.idle_since = self.time
        self.statustext(ML.MAV_SEVERITY_INFO, "Arming motors")
        return ML.MAV_RESULT_ACCEPTED

    def _disarm(self, text: str) -> None:
        self.armed = False
        self.idle_since = None
        self.guided_target = None
        self.takeoff_alt = None
        self.vn = self.ve = self.vd = 0.0
        self.statustext(ML.MAV_SEVERITY_INFO, text)

    def _takeoff(self, alt: float) -> int:
        if self.model != "copter":
            return ML.MAV_RESULT_UNSUPPORTED
        if (
            not self.armed
            or self.mode_name != "GUIDED"
            or not self.landed
            or not 0 < alt < math.inf
        ):
            return ML.MAV_RESULT_FAILED
        self.takeoff_alt = float(alt)
        self.landed = False
        self.idle_since = None
        return ML.MAV_RESULT_ACCEPTED

    def _reposition(self, p: tuple[float, ...]) -> int:
        if self.mode_name != "GUIDED" or not self.armed or (self.model == "copter" and self.landed):
            return ML.MAV_RESULT_FAILED
        if not _valid_latlon(p[4], p[5]) or math.isinf(p[6]):
            return ML.MAV_RESULT_DENIED  # ArduPilot: check_latlng, else DENIED
        alt = self.alt if math.isnan(p[6]) else float(p[6])
        self.guided_target = GeoPoint(p[4], p[5], alt)
        return ML.MAV_RESULT_ACCEPTED

    def _position_target(self, msg: Any) -> None:
        if self.mode_name != "GUIDED" or not self.armed:
            return  # ArduPilot ignores targets outside GUIDED, without an answer
        if self.model == "copter" and self.landed:
            return
        if msg.type_mask & 0b111:
            return  # position ignored: this double only flies to positions
        if msg.coordinate_frame not in (
            ML.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            ML.MAV_FRAME_GLOBAL_RELATIVE_ALT,
            ML.MAV_FRAME_GLOBAL_INT,
            ML.MAV_FRAME_GLOBAL,
        ):
            return
        if not _valid_latlon(msg.lat_int / 1e7, msg.lon_int / 1e7) or not math.isfinite(msg.alt):
            return  # ArduPilot drops targets that fail check_latlng
        alt = float(msg.alt)
        if msg.coordinate_frame in (ML.MAV_FRAME_GLOBAL_INT, ML.MAV_FRAME_GLOBAL):
            alt -= self.p.home.alt
        self.guided_target = GeoPoint(msg.lat_int / 1e7, msg.lon_int / 1e7, alt)
        self.takeoff_alt = None

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

    def _move(self, dt: float) -> None:
        name = self.mode_name
        self.vn = self.ve = self.vd = 0.0
        if self.model == "copter":
            if name == "GUIDED":
                if self.takeoff_alt is not None:
                    self._climb_to(self.takeoff_alt, dt)
                    if self.alt >= self.takeoff_alt - 0.05:
                        self.takeoff_alt = None
                        self.guided_target = GeoPoint(
                            self.position.lat, self.position.lon, self.alt
                        )
                elif self.guided_target is not None and not self.landed:
                    self._fly_to(self.guided_target, dt)
            elif name == "LAND":
                self._descend(dt)
            elif name == "RTL":
                self._rtl(dt)
        else:
            if name == "GUIDED" and self.guided_target is not None:
                self._drive_to(self.guided_target, dt)
            elif name == "RTL":
                home = GeoPoint(self.p.home.lat, self.p.home.lon, 0.0)
                self._drive_to(home, dt)

    def _climb_to(self, alt: float, dt: float) -> None:
        rate = self.p.climb_rate if alt > self.alt else -self.p.descent_rate
        step = rate * dt
        if abs(alt - self.alt) <= abs(step):
            self.alt = alt
        else:
            self.alt += step
            self.vd = -rate
        self.landed = False

    def _fly_to(self, target: GeoPoint, dt: float) -> None:
        self._horizontal(target, dt)
        if abs(target.alt - self.alt) > 1e-3:
            self._climb_to(max(target.alt, 0.0), dt)

    def _drive_to(self, target: GeoPoint, dt: float) -> None:
        self._horizontal(target, dt)

    def _horizontal(self, target: GeoPoint, dt: float) -> None:
        tn, te = north_east_m(self.p.home, target)
        dn, de = tn - self.north, te - self.east
        dist = math.hypot(dn, de)
        if dist < 1e-3:
            return
        step = self.p.cruise_speed * dt
        self.heading = math.degrees(math.atan2(de, dn)) % 360.0
        if dist <= step:
            self.north, self.east = tn, te
        else:
            self.north += dn / dist * step
            self.east += de / dist * step
            self.vn = dn / dist * self.p.cruise_speed
            self.ve = de / dist * self.p.cruise_speed

    def _descend(self, dt: float) -> None:
        if self.landed:
            return
        rate = self.p.descent_rate if self.alt > 10 else self.p.land_speed
        self.alt = max(0.0, self.alt - rate * dt)
        self.vd = rate
        if self.alt <= 0.0:
            self.landed = True
            self.vd = 0.0
            self._disarm("Land complete, disarming")

    def _rtl(self, dt: float) -> None:
        if self.landed:
            return
        home = GeoPoint(self.p.home.lat, self.p.home.lon, max(self.alt, self.p.rtl_alt))
        if self.rtl_phase == "climb":
            if self.alt < self.p.rtl_alt - 0.05:
                self._climb_to(self.p.rtl_alt, dt)
                return
            self.rtl_phase = "return"
        if self.rtl_phase == "return":
            if distance_m(self.position, home) > 0.5:
                self._horizontal(home, dt)
                return
            self.rtl_phase = "land"
        self._descend(dt)

    # --------------------------------------------------------------- telemetry
    def _stream(self) -> None:
        if self.time - self._last_heartbeat >= 1.0:
            self._last_heartbeat = self.time
            self._send_telemetry(ML.MAVLINK_MSG_ID_HEARTBEAT)
        for msg_id, interval in list(self.intervals.items()):
            if msg_id == ML.MAVLINK_MSG_ID_HEARTBEAT:
                continue
            if self.time - self._last_sent.get(msg_id, -math.inf) >= interval:
                self._last_sent[msg_id] = self.time
                self._send_telemetry(msg_id)

    def _send_telemetry(self, msg_id: int) -> bool:
        msg = self._telemetry(msg_id)
        if msg is None:
            return False
        self._send(msg)
        return True

    def _telemetry(self, msg_id: int) -> Any | None:
        boot_ms = int(self.time * 1000) & 0xFFFFFFFF
        if msg_id == ML.MAVLINK_MSG_ID_HEARTBEAT:
            return self._heartbeat()
        if msg_id == ML.MAVLINK_MSG_ID_GLOBAL_POSITION_INT:
            pos = self.position
            return self.mav.global_position_int_encode(
                boot_ms,
                int(pos.lat * 1e7),
                int(pos.lon * 1e7),
                int((self.p.home.alt + self.alt) * 1000),
                int(self.alt * 1000),
                int(self.vn * 100),
                int(self.ve * 100),
                int(self.vd * 100),
                int(self.heading * 100) % 36000,
            )
        if msg_id == ML.MAVLINK_MSG_ID_SYS_STATUS:
            sensors = (
                ML.MAV_SYS_STATUS_SENSOR_3D_GYRO
                | ML.MAV_SYS_STATUS_SENSOR_3D_ACCEL
                | ML.MAV_SYS_STATUS_SENSOR_GPS
                | ML.MAV_SYS_STATUS_AHRS
            )
            health = sensors | (ML.MAV_SYS_STATUS_PREARM_CHECK if self.ekf_ready else 0)
            return self.mav.sys_status_encode(
                sensors,
                sensors,
                health,
                200,
                self._voltage_mv(),
                1500 if self.armed else 50,
                round(self.battery),
                0,
                0,
                0,
                0,
                0,
                0,
            )
        if msg_id == ML.MAVLINK_MSG_ID_EKF_STATUS_REPORT:
            if self.time < 1.0:
                flags = EKF_FLAGS_BOOTING
            else:
                flags = EKF_FLAGS_GPS if self.ekf_ready else EKF_FLAGS_NO_GPS
            return self.mav.ekf_status_report_encode(flags, 0.02, 0.03, 0.01, 0.02, 0.0)
        if msg_id == ML.MAVLINK_MSG_ID_HOME_POSITION:
            if not self.ekf_ready:
                return None  # no home before the EKF has an origin
            home = self.p.home
            return self.mav.home_position_encode(
                int(home.lat * 1e7),
                int(home.lon * 1e7),
                int(home.alt * 1000),
                0.0,
                0.0,
                0.0,
                [1.0, 0.0, 0.0, 0.0],
                0.0,
                0.0,
                0.0,
            )
        if msg_id == ML.MAVLINK_MSG_ID_BATTERY_STATUS:
            cells = [self._voltage_mv() // 3] * 3 + [65535] * 7
            return self.mav.battery_status_encode(
                0, 0, 0, 32767, cells, 1500 if self.armed else 50, -1, -1, round(self.battery)
            )
        if msg_id == ML.MAVLINK_MSG_ID_VFR_HUD:
            return self.mav.vfr_hud_encode(
                math.hypot(self.vn, self.ve),
                math.hypot(self.vn, self.ve),
                int(self.heading),
                50 if self.armed else 0,
                self.p.home.alt + self.alt,
                -self.vd,
            )
        return None

    def _heartbeat(self) -> Any:
        base = ML.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | ML.MAV_MODE_FLAG_STABILIZE_ENABLED
        if self.mode_name in ("GUIDED", "AUTO", "RTL", "LOITER", "BRAKE", "HOLD", "LAND"):
            base |= ML.MAV_MODE_FLAG_GUIDED_ENABLED
        if self.armed:
            base |= ML.MAV_MODE_FLAG_SAFETY_ARMED
        if self.failsafe:
            state = ML.MAV_STATE_CRITICAL
        elif self.armed:
            state = ML.MAV_STATE_ACTIVE
        elif not self.booted:
            state = ML.MAV_STATE_BOOT
        else:
            state = ML.MAV_STATE_STANDBY
        mav_type = MAV_TYPE_QUADROTOR if self.model == "copter" else MAV_TYPE_GROUND_ROVER
        return self.mav.heartbeat_encode(
            mav_type, MAV_AUTOPILOT_ARDUPILOTMEGA, base, self.mode, state
        )

    def _voltage_mv(self) -> int:
        return int((10.5 + 2.1 * self.battery / 100.0) * 1000)

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


class _Collector:
    """File-like sink for pymavlink's encoder: keeps each packed frame."""

    def __init__(self, sink: list[bytes]) -> None:
        self._sink = sink

    def write(self, data: bytes) -> None:
        self._sink.append(bytes(data))


def _valid_latlon(lat: float, lon: float) -> bool:
    """ArduPilot's check_latlng: |lat| <= 90 and |lon| <= 180 degrees (NaN fails)."""
    return abs(lat) <= 90.0 and abs(lon) <= 180.0
