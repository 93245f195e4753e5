"""What the simulated vehicle reports: HEARTBEAT and the telemetry a client asks for.

Like ArduPilot, the double sends only HEARTBEAT (1 Hz) unasked; every other message
comes at the interval set with MAV_CMD_SET_MESSAGE_INTERVAL, or once on
MAV_CMD_REQUEST_MESSAGE. HOME_POSITION exists only once the EKF has an origin.
"""

from __future__ import annotations

import math
from typing import Any

from ..modes import MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_TYPE_GROUND_ROVER, MAV_TYPE_QUADROTOR
from .state import ML, SimState

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


class SimTelemetry(SimState):
    """Telemetry out of the simulated vehicle."""

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
        return self.gcs.telemetry(msg_id)

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
