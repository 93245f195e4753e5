"""What the vehicle double answers a ground station, the way ArduPilot 4.6 does.

Pointing Mission Planner, QGroundControl, MAVProxy or a pymavlink script at the
double should work as it does against a real vehicle:

* ``PARAM_REQUEST_LIST``: the firmware banner as STATUSTEXT, then every parameter
  as ``PARAM_VALUE`` with ``param_count`` and ``param_index`` 0..count-1;
* ``PARAM_REQUEST_READ``: by index (answered with that index) or by name (answered
  with index 65535, ArduPilot's -1); an unknown name or index gets no answer;
* ``PARAM_SET``: the stored value echoed with index 65535 (converted to the
  parameter's own type whatever type the request named); an unknown name, NaN or
  infinity gets no answer;
* ``REQUEST_DATA_STREAM``: the legacy stream groups at the requested rate (0 or
  ``start_stop`` 0 stops one; ``MAV_DATA_STREAM_ALL`` sets all but the parameter
  stream), kept in the ``SR0_*`` parameters as ArduPilot keeps them;
* ``MAV_CMD_REQUEST_MESSAGE`` for AUTOPILOT_VERSION and
  ``MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES``: COMMAND_ACK, then AUTOPILOT_VERSION
  with ArduPilot's capability bits and version number.

Messages addressed to another system or component are left alone.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any, Protocol

from pymavlink.dialects.v20 import ardupilotmega as ML

from ..geo import GeoPoint
from ..modes import Model
from .params import STREAM_PARAMS, Param, default_params

__all__ = ["EXTRA_TELEMETRY", "FIRMWARE_VERSION", "STREAMS", "GroundStationAnswers"]

FIRMWARE_VERSION = (4, 5, 0)
FIRMWARE_TYPE_OFFICIAL = 255
CAPABILITIES: dict[Model, int] = {"copter": 64495, "rover": 61935}
"""AUTOPILOT_VERSION.capabilities of ArduCopter / ArduRover 4.6 SITL: MISSION_FLOAT,
PARAM_FLOAT, MISSION_INT, COMMAND_INT, FTP, SET_ATTITUDE_TARGET,
SET_POSITION_TARGET_LOCAL_NED and _GLOBAL_INT, COMPASS_CALIBRATION, MAVLINK2,
MISSION_FENCE, MISSION_RALLY; the copter also TERRAIN and FLIGHT_TERMINATION."""

STREAMS: dict[int, str] = {
    ML.MAV_DATA_STREAM_RAW_SENSORS: "SR0_RAW_SENS",
    ML.MAV_DATA_STREAM_EXTENDED_STATUS: "SR0_EXT_STAT",
    ML.MAV_DATA_STREAM_RC_CHANNELS: "SR0_RC_CHAN",
    ML.MAV_DATA_STREAM_RAW_CONTROLLER: "SR0_RAW_CTRL",
    ML.MAV_DATA_STREAM_POSITION: "SR0_POSITION",
    ML.MAV_DATA_STREAM_EXTRA1: "SR0_EXTRA1",
    ML.MAV_DATA_STREAM_EXTRA2: "SR0_EXTRA2",
    ML.MAV_DATA_STREAM_EXTRA3: "SR0_EXTRA3",
}
"""MAV_DATA_STREAM id -> the SR0_ parameter holding its rate (Hz)."""

STREAM_MESSAGES: dict[str, tuple[int, ...]] = {
    "SR0_EXT_STAT": (ML.MAVLINK_MSG_ID_SYS_STATUS, ML.MAVLINK_MSG_ID_GPS_RAW_INT),
    "SR0_POSITION": (ML.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,),
    "SR0_EXTRA1": (ML.MAVLINK_MSG_ID_ATTITUDE,),
    "SR0_EXTRA2": (ML.MAVLINK_MSG_ID_VFR_HUD,),
    "SR0_EXTRA3": (ML.MAVLINK_MSG_ID_BATTERY_STATUS, ML.MAVLINK_MSG_ID_EKF_STATUS_REPORT),
}
"""The messages of each stream the double can send (ArduPilot's stream groups)."""
EXTRA_TELEMETRY = frozenset({ML.MAVLINK_MSG_ID_ATTITUDE, ML.MAVLINK_MSG_ID_GPS_RAW_INT})
"""Messages this module encodes (the vehicle encodes the others)."""

ANSWERED = frozenset(
    {"PARAM_REQUEST_LIST", "PARAM_REQUEST_READ", "PARAM_SET", "REQUEST_DATA_STREAM"}
)
PARAMS_PER_STEP = 50
"""Parameters sent per simulation step while a list is being fetched."""


class _Vehicle(Protocol):
    """What the answers need from :class:`~.sim.VehicleSim`."""

    p: Any
    """The vehicle's SimParams (bound parameters write into it)."""
    mav: Any
    intervals: dict[int, float]
    time: float
    alt: float
    heading: float
    vn: float
    ve: float
    vd: float
    ekf_ready: bool

    @property
    def position(self) -> GeoPoint: ...


BOUND: dict[str, tuple[str, float]] = {
    "RTL_ALT": ("rtl_alt", 100.0),
    "WPNAV_SPEED": ("cruise_speed", 100.0),
    "WPNAV_SPEED_UP": ("climb_rate", 100.0),
    "WPNAV_SPEED_DN": ("descent_rate", 100.0),
    "LAND_SPEED": ("land_speed", 100.0),
    "DISARM_DELAY": ("disarm_delay", 1.0),
    "WP_SPEED": ("cruise_speed", 1.0),
    "CRUISE_SPEED": ("cruise_speed", 1.0),
}
"""Parameter -> (SimParams attribute, parameter units per attribute unit): writing
the parameter changes how the double flies (RTL_ALT is in cm, rtl_alt in m)."""


class GroundStationAnswers:
    """Parameter, stream and version answers for one simulated vehicle."""

    def __init__(self, vehicle: _Vehicle, model: Model) -> None:
        self.vehicle = vehicle
        self.model = model
        self.mav = vehicle.mav
        self.params = default_params(model)
        p = vehicle.p
        for name, (attr, scale) in BOUND.items():
            self.params.update(name, getattr(p, attr) * scale)
        self.params.update("SYSID_THISMAV", p.system_id)
        self.params.on_set = self._param_changed
        self.system_id = p.system_id
        self.component_id = p.component_id
        self._queue: deque[int] = deque()

    def send(self, msg: Any) -> None:
        self.mav.send(msg)

    @property
    def intervals(self) -> dict[int, float]:
        return self.vehicle.intervals

    def _param_changed(self, param: Param) -> None:
        bound = BOUND.get(param.name)
        if bound is not None:
            attr, scale = bound
            setattr(self.vehicle.p, attr, param.value / scale)
        elif param.name in STREAM_PARAMS:
            self.apply_stream(param.name)

    # --------------------------------------------------------------- messages
    def handle(self, msg: Any) -> bool:
        """Answer ``msg`` if it is one of ours; False for everything else."""
        kind = msg.get_type()
        if kind not in ANSWERED:
            return False
        if not self._for_us(msg):
            return True
        if kind == "PARAM_REQUEST_LIST":
            self._banner()
            self._queue = deque(range(len(self.params)))
        elif kind == "PARAM_REQUEST_READ":
            self._read(_name(msg.param_id), int(msg.param_index))
        elif kind == "PARAM_SET":
            param = self.params.set(_name(msg.param_id), float(msg.param_value))
            if param is not None:
                self._param_value(param, -1)
        else:
            self._data_stream(int(msg.req_stream_id), int(msg.req_message_rate), msg.start_stop)
        return True

    def _for_us(self, msg: Any) -> bool:
        system = getattr(msg, "target_system", 0)
        component = getattr(msg, "target_component", 0)
        return system in (0, self.system_id) and component in (0, self.component_id)

    def _read(self, name: str, index: int) -> None:
        if index != -1:
            param = self.params.at(index)
            if param is not None:
                self._param_value(param, index)
            return
        param = self.params.get(name)
        if param is not None:
            self._param_value(param, -1)

    def _param_value(self, param: Param, index: int) -> None:
        self.send(
            self.mav.param_value_encode(
                param.name.encode(), param.value, param.type, len(self.params), index & 0xFFFF
            )
        )

    def _banner(self) -> None:
        major, minor, patch = FIRMWARE_VERSION
        name = "ArduCopter" if self.model == "copter" else "ArduRover"
        texts = [f"{name} V{major}.{minor}.{patch} (double)"]
        if self.model == "copter":
            texts.append("Frame: QUAD/PLUS")
        for text in texts:
            self.send(self.mav.statustext_encode(ML.MAV_SEVERITY_INFO, text.encode()))

    # ---------------------------------------------------------------- streams
    def _data_stream(self, stream: int, rate: int, start_stop: int) -> None:
        if start_stop not in (0, 1):
            return
        hz = float(rate) if start_stop == 1 else 0.0
        if stream == ML.MAV_DATA_STREAM_ALL:
            for name in STREAM_PARAMS:
                if name != "SR0_PARAMS":
                    self.params.update(name, hz)
                    self.apply_stream(name)
            return
        found = STREAMS.get(stream)
        if found is not None:
            self.params.update(found, hz)
            self.apply_stream(found)

    def apply_stream(self, name: str) -> None:
        """Send the messages of stream ``name`` at the rate its parameter holds."""
        param = self.params.get(name)
        if param is None:
            return
        hz = param.value
        for msg_id in STREAM_MESSAGES.get(name, ()):
            if hz > 0:
                self.intervals[msg_id] = 1.0 / hz
            else:
                self.intervals.pop(msg_id, None)

    # --------------------------------------------------------------- commands
    def command(self, command: int, p: tuple[float, ...]) -> int | None:
        """The COMMAND_ACK result for a command this module answers, else None;
        the answer itself is sent by :meth:`after_ack`."""
        if command == ML.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES:
            return ML.MAV_RESULT_ACCEPTED
        if command == ML.MAV_CMD_REQUEST_MESSAGE and p[0] == ML.MAVLINK_MSG_ID_AUTOPILOT_VERSION:
            return ML.MAV_RESULT_ACCEPTED
        return None

    def after_ack(self, command: int, p: tuple[float, ...]) -> None:
        """What follows the COMMAND_ACK of a command :meth:`command` accepted."""
        if self.command(command, p) == ML.MAV_RESULT_ACCEPTED:
            self.send(self.autopilot_version())

    def autopilot_version(self) -> Any:
        major, minor, patch = FIRMWARE_VERSION
        version = (major << 24) | (minor << 16) | (patch << 8) | FIRMWARE_TYPE_OFFICIAL
        return self.mav.autopilot_version_encode(
            CAPABILITIES[self.model],
            version,
            0,
            0,
            0,
            list(b"d0ub1e00"),
            [0] * 8,
            [0] * 8,
            0,
            0,
            0,
            [0] * 18,
        )

    def telemetry(self, msg_id: int) -> Any | None:
        """ATTITUDE and GPS_RAW_INT, which ground stations draw their instruments from."""
        v = self.vehicle
        if msg_id == ML.MAVLINK_MSG_ID_ATTITUDE:
            yaw = math.radians(v.heading)
            yaw = yaw - 2 * math.pi if yaw > math.pi else yaw
            return self.mav.attitude_encode(_boot_ms(v.time), 0.0, 0.0, yaw, 0.0, 0.0, 0.0)
        if msg_id == ML.MAVLINK_MSG_ID_GPS_RAW_INT:
            pos = v.position
            fix = ML.GPS_FIX_TYPE_3D_FIX if v.time >= 1.0 else ML.GPS_FIX_TYPE_NO_FIX
            speed = math.hypot(v.vn, v.ve)
            return self.mav.gps_raw_int_encode(
                int(v.time * 1e6),
                fix,
                int(pos.lat * 1e7),
                int(pos.lon * 1e7),
                int((v.p.home.alt + v.alt) * 1000),
                121,
                65535,
                int(speed * 100),
                int(v.heading * 100) % 36000,
                10,
            )
        return None

    # ------------------------------------------------------------------- time
    def step(self) -> None:
        """Send the next parameters of a list being fetched."""
        for _ in range(min(PARAMS_PER_STEP, len(self._queue))):
            index = self._queue.popleft()
            param = self.params.at(index)
            if param is not None:
                self._param_value(param, index)


def _name(raw: Any) -> str:
    text = raw.decode(errors="replace") if isinstance(raw, bytes) else str(raw)
    return text.split("\0", 1)[0]


def _boot_ms(seconds: float) -> int:
    return int(seconds * 1000) & 0xFFFFFFFF
