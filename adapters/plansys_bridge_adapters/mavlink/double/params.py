"""The vehicle double's parameters, typed and converted as ArduPilot's AP_Param does.

A ground station reads a vehicle's parameters before anything else (Mission
Planner, QGroundControl and MAVProxy all fetch the full list on connect), so the
double keeps a parameter table: names, MAVLink types and values as ArduCopter /
ArduRover 4.6 report them for the settings the double models. Some are bound to
its behaviour: writing ``RTL_ALT``, ``WPNAV_SPEED`` or ``DISARM_DELAY`` changes how
it flies, and the ``SR0_*`` stream rates are the telemetry rates it sends at (a
``REQUEST_DATA_STREAM`` sets them, as it does on ArduPilot).

Values go over MAVLink as floats whatever their type (ArduPilot's
``MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT``); a value written to an integer parameter
is truncated toward zero and clamped to the type's range, as ``AP_Param::set_float``
does (``TELEM_DELAY`` set to 300 reads back 127).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as ML

from ..modes import Model

__all__ = ["Param", "ParamTable", "default_params"]

INT8, INT16, INT32, REAL32 = (
    ML.MAV_PARAM_TYPE_INT8,
    ML.MAV_PARAM_TYPE_INT16,
    ML.MAV_PARAM_TYPE_INT32,
    ML.MAV_PARAM_TYPE_REAL32,
)
_RANGES = {INT8: (-128, 127), INT16: (-32768, 32767), INT32: (-(2**31), 2**31 - 1)}
NAME_LENGTH = 16
"""``param_id`` is a char[16]: longer names do not exist on the wire."""


@dataclass
class Param:
    name: str
    type: int
    """MAV_PARAM_TYPE_INT8 / INT16 / INT32 / REAL32."""
    value: float


def convert(value: float, kind: int) -> float:
    """``value`` as a parameter of type ``kind`` stores it (ArduPilot's set_float)."""
    if kind == REAL32:
        return float(struct.unpack("<f", struct.pack("<f", value))[0])
    low, high = _RANGES[kind]
    return float(min(high, max(low, math.trunc(value))))


class ParamTable:
    """Parameters in ArduPilot's order; ``on_set`` hears every accepted write."""

    def __init__(self, params: Iterable[Param]) -> None:
        self._list = list(params)
        self._index = {p.name: i for i, p in enumerate(self._list)}
        self.on_set: Callable[[Param], None] | None = None

    def __len__(self) -> int:
        return len(self._list)

    def __iter__(self) -> Iterator[Param]:
        return iter(self._list)

    def index_of(self, name: str) -> int | None:
        return self._index.get(name)

    def get(self, name: str) -> Param | None:
        i = self._index.get(name)
        return None if i is None else self._list[i]

    def at(self, index: int) -> Param | None:
        return self._list[index] if 0 <= index < len(self._list) else None

    def set(self, name: str, value: float) -> Param | None:
        """Write a parameter; None (nothing changed) for an unknown name or a NaN or
        infinite value, which ArduPilot ignores without an answer."""
        param = self.get(name)
        if param is None or not math.isfinite(value):
            return None
        param.value = convert(value, param.type)
        if self.on_set is not None:
            self.on_set(param)
        return param

    def update(self, name: str, value: float) -> None:
        """The vehicle changed a value itself (a stream rate, a speed): no echo."""
        param = self.get(name)
        if param is not None:
            param.value = convert(value, param.type)


STREAM_PARAMS = (
    "SR0_RAW_SENS",
    "SR0_EXT_STAT",
    "SR0_RC_CHAN",
    "SR0_RAW_CTRL",
    "SR0_POSITION",
    "SR0_EXTRA1",
    "SR0_EXTRA2",
    "SR0_EXTRA3",
    "SR0_PARAMS",
    "SR0_ADSB",
)

_COMMON_HEAD: tuple[tuple[str, int, float], ...] = (
    ("SYSID_THISMAV", INT16, 1),
    ("SYSID_MYGCS", INT16, 255),
)
_COPTER: tuple[tuple[str, int, float], ...] = (
    ("FORMAT_VERSION", INT16, 120),
    *_COMMON_HEAD,
    ("PILOT_SPEED_UP", INT16, 250),
    ("PILOT_TKOFF_ALT", REAL32, 0),
    ("TELEM_DELAY", INT8, 0),
    ("RTL_ALT", INT32, 1500),
    ("RTL_SPEED", INT16, 0),
    ("RTL_ALT_FINAL", INT16, 0),
    ("RTL_LOIT_TIME", INT32, 5000),
    ("FS_GCS_ENABLE", INT8, 0),
    ("FS_THR_ENABLE", INT8, 1),
    ("FS_EKF_ACTION", INT8, 1),
    ("FS_OPTIONS", INT32, 16),
    ("LAND_SPEED", INT16, 50),
    ("LAND_SPEED_HIGH", INT16, 0),
    ("LAND_ALT_LOW", INT16, 1000),
    ("FLTMODE1", INT8, 7),
    ("FLTMODE2", INT8, 9),
    ("FLTMODE3", INT8, 6),
    ("FLTMODE4", INT8, 3),
    ("FLTMODE5", INT8, 5),
    ("FLTMODE6", INT8, 0),
    ("FLTMODE_CH", INT8, 5),
    ("INITIAL_MODE", INT8, 0),
    ("DISARM_DELAY", INT8, 10),
    ("ANGLE_MAX", INT16, 3000),
    ("FRAME_CLASS", INT8, 1),
    ("FRAME_TYPE", INT8, 0),
    ("WP_YAW_BEHAVIOR", INT8, 2),
    ("WPNAV_SPEED", REAL32, 1000),
    ("WPNAV_RADIUS", REAL32, 200),
    ("WPNAV_SPEED_UP", REAL32, 250),
    ("WPNAV_SPEED_DN", REAL32, 150),
    ("WPNAV_ACCEL", REAL32, 250),
)
_ROVER: tuple[tuple[str, int, float], ...] = (
    ("FORMAT_VERSION", INT16, 16),
    *_COMMON_HEAD,
    ("INITIAL_MODE", INT8, 0),
    ("CRUISE_THROTTLE", INT8, 30),
    ("CRUISE_SPEED", REAL32, 5),
    ("WP_SPEED", REAL32, 5),
    ("WP_RADIUS", REAL32, 2),
    ("RTL_SPEED", REAL32, 0),
    ("FS_ACTION", INT8, 2),
    ("FS_TIMEOUT", REAL32, 1.5),
    ("FS_GCS_ENABLE", INT8, 0),
    ("FS_THR_ENABLE", INT8, 1),
    ("MODE_CH", INT8, 8),
    ("MODE1", INT8, 0),
    ("MODE2", INT8, 0),
    ("MODE3", INT8, 11),
    ("MODE4", INT8, 10),
    ("MODE5", INT8, 2),
    ("MODE6", INT8, 0),
    ("FRAME_CLASS", INT8, 1),
)
_COMMON_TAIL: tuple[tuple[str, int, float], ...] = (
    ("ARMING_CHECK", INT32, 1),
    ("BATT_MONITOR", INT8, 4),
    ("BATT_CAPACITY", INT32, 3300),
    ("BATT_LOW_VOLT", REAL32, 10.5),
    ("BATT_CRT_VOLT", REAL32, 0),
    ("BATT_FS_LOW_ACT", INT8, 0),
    ("BATT_FS_CRT_ACT", INT8, 0),
    ("SERIAL0_BAUD", INT32, 115),
    ("SERIAL0_PROTOCOL", INT8, 2),
    ("AHRS_EKF_TYPE", INT8, 3),
    ("EK3_ENABLE", INT8, 1),
    *((name, INT16, 0) for name in STREAM_PARAMS),
    ("STAT_RUNTIME", INT32, 0),
)


def default_params(model: Model) -> ParamTable:
    """The double's table for ``model`` (values as ArduPilot 4.6 SITL reports them)."""
    body = _COPTER if model == "copter" else _ROVER
    return ParamTable(Param(n, t, convert(v, t)) for n, t, v in (*body, *_COMMON_TAIL))
