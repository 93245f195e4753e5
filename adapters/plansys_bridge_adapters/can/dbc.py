"""The mobile base's CAN messages, described by a DBC file and decoded with cantools.

The DBC is the contract between the planner side and the base: frame IDs, scales,
signedness and ranges live there, not in code. This module turns raw frames into
typed, frozen dataclasses and back, so the rest of the adapter never touches bytes.
A user with a base whose IDs differ can ship their own DBC as long as it keeps the
message and signal names; :meth:`MobileBaseDbc.load` checks them up front and says
which one is missing.

Decoding is defensive: an unknown ID, a wrong length (DLC), a remote frame or a
signal outside its DBC range raises :class:`MalformedFrame` with a ``kind`` the
caller counts, instead of producing nonsense numbers.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import IntEnum
from importlib import resources
from pathlib import Path
from typing import Any, Literal, TypeAlias

import can
import cantools
from cantools.database.can import Database
from cantools.database.can import Message as DbcMessage

from plansys_bridge.errors import AdapterError

DEFAULT_DBC_NAME = "mobile_base.dbc"

MalformedKind: TypeAlias = Literal[
    "unknown_id", "bad_dlc", "remote", "out_of_range", "undecodable", "outgoing"
]


class DbcError(AdapterError):
    """The DBC file cannot be read or lacks a message/signal the adapter needs."""


class MalformedFrame(AdapterError):
    """A frame on the bus that is not a valid mobile-base message.

    ``kind`` classifies it for counters; the text names the frame ID and why.
    """

    def __init__(self, kind: MalformedKind, frame_id: int, reason: str) -> None:
        self.kind: MalformedKind = kind
        self.frame_id = frame_id
        super().__init__(f"CAN frame 0x{frame_id:03X}: {reason}")


class BaseState(IntEnum):
    """``BASE_Status.BaseState`` (the DBC's value table)."""

    INIT = 0
    IDLE = 1
    DRIVING = 2
    STOPPED = 3
    ESTOP = 4
    FAULT = 5


@dataclass(frozen=True)
class FaultBits:
    """Fault flags of ``BASE_Status``."""

    motor: bool = False
    overcurrent: bool = False
    estop: bool = False
    watchdog: bool = False

    @property
    def any(self) -> bool:
        return self.motor or self.overcurrent or self.estop or self.watchdog

    def names(self) -> list[str]:
        """Human-readable names of the set bits, in DBC order."""
        labels = (
            (self.motor, "motor fault"),
            (self.overcurrent, "overcurrent"),
            (self.estop, "e-stop active"),
            (self.watchdog, "watchdog tripped"),
        )
        return [label for flag, label in labels if flag]


@dataclass(frozen=True)
class VelocityCommand:
    """``BASE_VelocityCmd``: set-points in m/s and rad/s (CCW positive)."""

    linear: float
    angular: float
    enable: bool = True
    counter: int = 0


@dataclass(frozen=True)
class EStopCommand:
    """``BASE_EStopCmd``: engage (True) or release (False) the e-stop."""

    engage: bool
    counter: int = 0


@dataclass(frozen=True)
class OdomPose:
    """``BASE_OdomPose``: position in metres and heading in radians, odom frame."""

    x: float
    y: float
    yaw: float


@dataclass(frozen=True)
class OdomTwist:
    """``BASE_OdomTwist``: measured velocities."""

    linear: float
    angular: float
    counter: int = 0


@dataclass(frozen=True)
class BaseStatus:
    """``BASE_Status``: battery, faults, state machine and heartbeat counter."""

    battery_percent: float
    battery_voltage: float
    faults: FaultBits
    state: BaseState
    counter: int = 0


Frame: TypeAlias = VelocityCommand | EStopCommand | OdomPose | OdomTwist | BaseStatus


def normalize_angle(angle: float) -> float:
    """Wrap an angle to [-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def _velocity_to_signals(f: VelocityCommand) -> dict[str, Any]:
    return {
        "CmdLinear": f.linear,
        "CmdAngular": f.angular,
        "CmdEnable": int(f.enable),
        "CmdCounter": f.counter % 16,
    }


def _velocity_from_signals(s: Mapping[str, Any]) -> VelocityCommand:
    return VelocityCommand(
        float(s["CmdLinear"]), float(s["CmdAngular"]), bool(s["CmdEnable"]), int(s["CmdCounter"])
    )


def _estop_to_signals(f: EStopCommand) -> dict[str, Any]:
    return {"EStopRequest": int(f.engage), "EStopCounter": f.counter % 16}


def _estop_from_signals(s: Mapping[str, Any]) -> EStopCommand:
    return EStopCommand(bool(s["EStopRequest"]), int(s["EStopCounter"]))


def _pose_to_signals(f: OdomPose) -> dict[str, Any]:
    return {"PoseX": f.x, "PoseY": f.y, "PoseYaw": normalize_angle(f.yaw)}


def _pose_from_signals(s: Mapping[str, Any]) -> OdomPose:
    return OdomPose(float(s["PoseX"]), float(s["PoseY"]), float(s["PoseYaw"]))


def _twist_to_signals(f: OdomTwist) -> dict[str, Any]:
    return {"TwistLinear": f.linear, "TwistAngular": f.angular, "OdomCounter": f.counter % 256}


def _twist_from_signals(s: Mapping[str, Any]) -> OdomTwist:
    return OdomTwist(float(s["TwistLinear"]), float(s["TwistAngular"]), int(s["OdomCounter"]))


def _status_to_signals(f: BaseStatus) -> dict[str, Any]:
    return {
        "BatteryPercent": f.battery_percent,
        "BatteryVoltage": f.battery_voltage,
        "FaultMotor": int(f.faults.motor),
        "FaultOvercurrent": int(f.faults.overcurrent),
        "FaultEStop": int(f.faults.estop),
        "FaultWatchdog": int(f.faults.watchdog),
        "BaseState": int(f.state),
        "HeartbeatCounter": f.counter % 256,
    }


def _status_from_signals(s: Mapping[str, Any]) -> BaseStatus:
    faults = FaultBits(
        motor=bool(s["FaultMotor"]),
        overcurrent=bool(s["FaultOvercurrent"]),
        estop=bool(s["FaultEStop"]),
        watchdog=bool(s["FaultWatchdog"]),
    )
    return BaseStatus(
        float(s["BatteryPercent"]),
        float(s["BatteryVoltage"]),
        faults,
        BaseState(int(s["BaseState"])),
        int(s["HeartbeatCounter"]),
    )


@dataclass(frozen=True)
class _Codec:
    message: str
    signals: tuple[str, ...]
    to_signals: Callable[[Any], dict[str, Any]]
    from_signals: Callable[[Mapping[str, Any]], Frame]


_CODECS: dict[type, _Codec] = {
    VelocityCommand: _Codec(
        "BASE_VelocityCmd",
        ("CmdLinear", "CmdAngular", "CmdEnable", "CmdCounter"),
        _velocity_to_signals,
        _velocity_from_signals,
    ),
    EStopCommand: _Codec(
        "BASE_EStopCmd", ("EStopRequest", "EStopCounter"), _estop_to_signals, _estop_from_signals
    ),
    OdomPose: _Codec(
        "BASE_OdomPose", ("PoseX", "PoseY", "PoseYaw"), _pose_to_signals, _pose_from_signals
    ),
    OdomTwist: _Codec(
        "BASE_OdomTwist",
        ("TwistLinear", "TwistAngular", "OdomCounter"),
        _twist_to_signals,
        _twist_from_signals,
    ),
    BaseStatus: _Codec(
        "BASE_Status",
        (
            "BatteryPercent",
            "BatteryVoltage",
            "FaultMotor",
            "FaultOvercurrent",
            "FaultEStop",
            "FaultWatchdog",
            "BaseState",
            "HeartbeatCounter",
        ),
        _status_to_signals,
        _status_from_signals,
    ),
}

FRAME_TYPES: tuple[type, ...] = tuple(_CODECS)
"""Every typed frame this module encodes and decodes."""


def default_dbc_path() -> Path:
    """The DBC shipped with the package (``mobile_base.dbc``)."""
    return Path(str(resources.files(__package__).joinpath(DEFAULT_DBC_NAME)))


class MobileBaseDbc:
    """Typed encode/decode of the mobile-base messages of one DBC database."""

    def __init__(self, database: Database, source: str = "<dbc>") -> None:
        self.database = database
        self.source = source
        self._by_type: dict[type, DbcMessage] = {}
        self._by_id: dict[tuple[int, bool], tuple[DbcMessage, _Codec]] = {}
        for frame_type, codec in _CODECS.items():
            try:
                message = database.get_message_by_name(codec.message)
            except KeyError as exc:
                raise DbcError(f"{source}: message {codec.message} is missing") from exc
            names = {signal.name for signal in message.signals}
            for signal_name in codec.signals:
                if signal_name not in names:
                    raise DbcError(f"{source}: {codec.message} has no signal {signal_name}")
            self._by_type[frame_type] = message
            self._by_id[(message.frame_id, message.is_extended_frame)] = (message, codec)

    @classmethod
    def load(cls, path: str | Path | None = None) -> MobileBaseDbc:
        """Read a DBC file (the packaged one when ``path`` is None)."""
        dbc_path = Path(path) if path is not None else default_dbc_path()
        try:
            database = cantools.database.load_file(str(dbc_path), database_format="dbc")
        except FileNotFoundError as exc:
            raise DbcError(f"{dbc_path}: DBC file not found") from exc
        except (OSError, cantools.database.UnsupportedDatabaseFormatError) as exc:
            raise DbcError(f"{dbc_path}: not a readable DBC file: {exc}") from exc
        if not isinstance(database, Database):
            raise DbcError(f"{dbc_path}: not a CAN database")
        return cls(database, str(dbc_path))

    def message_for(self, frame_type: type) -> DbcMessage:
        """The cantools message describing ``frame_type``."""
        return self._by_type[frame_type]

    def frame_id(self, frame_type: type) -> int:
        return self._by_type[frame_type].frame_id

    def encode(self, frame: Frame) -> can.Message:
        """Encode a typed frame; values outside the DBC range raise AdapterError."""
        codec = _CODECS[type(frame)]
        message = self._by_type[type(frame)]
        try:
            data = message.encode(codec.to_signals(frame), scaling=True, strict=True)
        except (cantools.database.EncodeError, ValueError, KeyError) as exc:
            raise AdapterError(f"cannot encode {message.name} {frame}: {exc}") from exc
        return can.Message(
            arbitration_id=message.frame_id,
            is_extended_id=message.is_extended_frame,
            data=data,
            dlc=len(data),
        )

    def decode(self, msg: can.Message) -> Frame:
        """Decode a received frame, raising :class:`MalformedFrame` when it is not valid."""
        frame_id = msg.arbitration_id
        entry = self._by_id.get((frame_id, bool(msg.is_extended_id)))
        if entry is None:
            kind = "extended" if msg.is_extended_id else "standard"
            raise MalformedFrame("unknown_id", frame_id, f"unknown {kind} ID")
        message, codec = entry
        if msg.is_remote_frame:
            raise MalformedFrame("remote", frame_id, f"remote frame for {message.name}")
        if len(msg.data) != message.length:
            raise MalformedFrame(
                "bad_dlc",
                frame_id,
                f"{message.name} needs {message.length} bytes, got {len(msg.data)}",
            )
        try:
            signals = message.decode(bytes(msg.data), decode_choices=False, scaling=True)
        except (cantools.database.DecodeError, ValueError) as exc:
            raise MalformedFrame("undecodable", frame_id, f"{message.name}: {exc}") from exc
        assert isinstance(signals, dict)
        for signal in message.signals:
            value = signals.get(signal.name)
            if not isinstance(value, int | float):
                continue
            margin = abs(signal.scale) / 2
            low = signal.minimum
            high = signal.maximum
            if (low is not None and value < low - margin) or (
                high is not None and value > high + margin
            ):
                raise MalformedFrame(
                    "out_of_range",
                    frame_id,
                    f"{message.name}.{signal.name}={value} outside [{low}, {high}]",
                )
        return codec.from_signals(signals)
