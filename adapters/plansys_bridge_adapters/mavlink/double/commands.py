"""What the simulated vehicle does with a ground station's messages.

COMMAND_LONG / COMMAND_INT, SET_MODE and SET_POSITION_TARGET_GLOBAL_INT, answered
the way ArduPilot answers them: the same COMMAND_ACK results, the same STATUSTEXT
reasons for a refused arm or mode change, targets outside GUIDED ignored without an
answer. Tests can make the next command refused or its ACK lost.
"""

from __future__ import annotations

import math
from typing import Any

from ..geo import GeoPoint
from ..modes import mode_name, mode_number, mode_table
from .ground_station import EXTRA_TELEMETRY
from .state import ML
from .telemetry import STREAMABLE, SimTelemetry

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


class SimCommands(SimTelemetry):
    """Commands into the simulated vehicle."""

    def handle(self, msg: Any) -> None:
        """React to one decoded message from the ground station."""
        if self.link_down or self.gcs.handle(msg):
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
        answered = self.gcs.command(command, p)
        if answered is not None:
            self._ack(command, answered)
            self.gcs.after_ack(command, p)
        elif command == ML.MAV_CMD_SET_MESSAGE_INTERVAL:
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
        if msg_id not in STREAMABLE | EXTRA_TELEMETRY:
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


def _valid_latlon(lat: float, lon: float) -> bool:
    """ArduPilot's check_latlng: |lat| <= 90 and |lon| <= 180 degrees (NaN fails)."""
    return abs(lat) <= 90.0 and abs(lon) <= 180.0
