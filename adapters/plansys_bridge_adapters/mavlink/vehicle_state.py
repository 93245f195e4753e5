"""What a ground station knows of its vehicle: the latest telemetry and STATUSTEXTs.

:class:`Telemetry` keeps the last value of each message the client relies on
(position, battery, EKF, home, arming and mode from HEARTBEAT) and reads them out of
the decoded pymavlink messages; the vehicle client decides what a change means.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from .geo import GeoPoint

ML: Any = mavlink2

EKF_NEEDED = 0x01 | 0x02 | 0x10 | 0x20
"""EKF_ATTITUDE | EKF_VELOCITY_HORIZ | EKF_POS_HORIZ_ABS | EKF_POS_VERT_ABS."""
EKF_BAD = 0x80 | 0x400
"""EKF_CONST_POS_MODE | EKF_UNINITIALIZED: no usable position yet."""


def enum_name(enum: str, value: int) -> str:
    """The MAVLink name of ``value`` in ``enum`` (``MAV_RESULT_DENIED``), or ``ENUM(n)``."""
    entry = ML.enums.get(enum, {}).get(value)
    return entry.name if entry is not None else f"{enum}({value})"


@dataclass(frozen=True)
class StatusText:
    stamp: float
    severity: int
    text: str

    @property
    def severity_name(self) -> str:
        return enum_name("MAV_SEVERITY", self.severity)


def statustext_of(msg: Any, stamp: float) -> StatusText:
    """A STATUSTEXT message as text, without the padding NULs."""
    text = msg.text if isinstance(msg.text, str) else msg.text.decode(errors="replace")
    return StatusText(stamp, int(msg.severity), text.rstrip("\x00").strip())


@dataclass
class Telemetry:
    """The latest values heard from the vehicle (None until first heard)."""

    position: GeoPoint | None = None
    """Latitude, longitude and altitude above home (GLOBAL_POSITION_INT.relative_alt)."""
    position_time: float | None = None
    """The vehicle's own time of :attr:`position`: seconds since it booted (time_boot_ms)."""
    alt_amsl: float | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """North, east, down in m/s."""
    heading: float | None = None
    battery_remaining: float | None = None
    """Percent (SYS_STATUS.battery_remaining); None when the vehicle does not know."""
    battery_voltage: float | None = None
    ekf_flags: int | None = None
    home: GeoPoint | None = None
    """Home with its altitude above mean sea level."""
    armed: bool = False
    custom_mode: int | None = None
    system_status: int | None = None
    mav_type: int | None = None
    last_heartbeat: float = -math.inf

    def ekf_ready(self) -> bool:
        """EKF_STATUS_REPORT says the EKF has an absolute position."""
        flags = self.ekf_flags
        return flags is not None and flags & EKF_NEEDED == EKF_NEEDED and not flags & EKF_BAD

    def read_heartbeat(self, msg: Any, stamp: float) -> None:
        self.last_heartbeat = stamp
        self.armed = bool(msg.base_mode & ML.MAV_MODE_FLAG_SAFETY_ARMED)
        self.custom_mode = int(msg.custom_mode)
        self.system_status = int(msg.system_status)
        self.mav_type = int(msg.type)

    def read_position(self, msg: Any) -> None:
        self.position = GeoPoint(msg.lat / 1e7, msg.lon / 1e7, msg.relative_alt / 1000.0)
        self.position_time = msg.time_boot_ms / 1000.0
        self.alt_amsl = msg.alt / 1000.0
        self.velocity = (msg.vx / 100.0, msg.vy / 100.0, msg.vz / 100.0)
        self.heading = None if msg.hdg == 65535 else msg.hdg / 100.0

    def read_sys_status(self, msg: Any) -> None:
        self.battery_remaining = None if msg.battery_remaining < 0 else float(msg.battery_remaining)
        self.battery_voltage = None if msg.voltage_battery == 65535 else msg.voltage_battery / 1000

    def read_ekf(self, msg: Any) -> None:
        self.ekf_flags = int(msg.flags)

    def read_home(self, msg: Any) -> None:
        self.home = GeoPoint(msg.latitude / 1e7, msg.longitude / 1e7, msg.altitude / 1e3)
