"""The kind-specific keys of a ``kind: mavlink`` performer entry, as a pydantic model.

:class:`MavlinkEntry` is the performer's ``Settings``: validated when the mission
loads, so a mistake (``url: tpc:127.0.0.1:5760``, ``commands.fly.do: hover``) is one
error naming its key, line and column before any link is opened. :func:`resolve`
then loads the locations and gives the performer its :class:`MavlinkSettings`.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, ValidationInfo, field_validator, model_validator

from plansys_bridge.errors import ConfigError
from plansys_bridge.plugins import PluginSettings

from .locations import LocationMap, load_locations
from .modes import Model
from .safety import SAFE_MODES
from .telemetry import TelemetryConfig
from .vehicle import DEFAULT_TELEMETRY_HZ

DOES = ("takeoff", "goto", "land", "rtl", "hold")


@dataclass(frozen=True)
class Command:
    """What one PDDL action does on the vehicle."""

    do: str
    vehicle_arg: int | None = None
    target_arg: int = -1
    altitude: float | None = None
    seconds: float | None = None
    takeoff: bool = False
    """goto: a copter on the ground takes off (to ``altitude``) first."""


class CommandSettings(PluginSettings):
    """``{do: goto, vehicle_arg: 0, target_arg: 2, ...}`` or just ``goto``."""

    do: Literal["takeoff", "goto", "land", "rtl", "hold"]
    vehicle_arg: int | None = Field(None, ge=0)
    """Position of the vehicle's PDDL object among the action's arguments (0 = first)."""
    target_arg: int = -1
    """Position of the destination (-1 = the last argument)."""
    altitude: float | None = Field(None, gt=0)
    seconds: float | None = Field(None, gt=0)
    takeoff: bool = False

    @model_validator(mode="before")
    @classmethod
    def _short_form(cls, value: object) -> object:
        return {"do": value} if isinstance(value, str) else value

    @field_validator("takeoff")
    @classmethod
    def _takeoff_on_goto(cls, value: bool, info: ValidationInfo) -> bool:
        if value and info.data.get("do") != "goto":
            raise ValueError("takeoff applies to a goto command")
        return value


class Timeouts(PluginSettings):
    """Seconds (wall clock): link, heartbeat loss, COMMAND_ACK, EKF, arming, one action."""

    connect: float = Field(30.0, gt=0)
    heartbeat: float = Field(3.0, gt=0)
    command: float = Field(1.0, gt=0)
    ekf: float = Field(120.0, gt=0)
    arm: float = Field(30.0, gt=0)
    action: float = Field(600.0, gt=0)
    stall: float = Field(20.0, gt=0)
    """Seconds of the vehicle's own time a go-to may go without getting closer."""


class HomeSettings(PluginSettings):
    lat: float = Field(ge=-90, le=90)
    lon: float = Field(ge=-180, le=180)
    alt: float = 584.0


class DoubleSettings(PluginSettings):
    """``double:`` the simulated vehicle started in-process instead of a link."""

    model: Model = "copter"
    speedup: float | None = Field(None, gt=0)
    transport: Literal["tcp", "udp"] | None = None
    ekf_delay: float | None = Field(None, gt=0)
    home: HomeSettings | None = None
    disarm_delay: float | None = Field(None, gt=0)
    cruise_speed: float | None = Field(None, gt=0)
    battery_failsafe_pct: float | None = Field(None, ge=0, le=100)
    battery_capacity_s: float | None = Field(None, gt=0)
    position_modes_need_ekf: bool | None = None


class TelemetrySettings(PluginSettings):
    """``telemetry:`` the battery written into the knowledge (:class:`TelemetryConfig`)."""

    battery_function: str | None = Field(None, pattern=r"\S")
    low_battery_predicate: str | None = Field(None, pattern=r"\S")
    low_battery_threshold: float = Field(25.0, ge=0)
    hysteresis: float = Field(5.0, ge=0)
    battery_step: float = Field(1.0, ge=0)


NETWORK_SCHEMES = ("tcp", "tcpin", "udp", "udpin", "udpout", "udpbcast")


def url_problem(url: str) -> str | None:
    """What is wrong with a link URL, found before any link opens (None: nothing).

    pymavlink reads anything that is not a network URL as a serial device, so a
    misspelt scheme (``tpc:127.0.0.1:5760``) would otherwise wait out the connect
    timeout on a device that does not exist.
    """
    scheme, sep, rest = url.partition(":")
    if scheme in NETWORK_SCHEMES:
        host, _, port = rest.rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            return f"a network URL must look like {scheme}:HOST:PORT"
        return None
    if not sep or scheme == "serial" or url.startswith(("/", ".")):
        return None  # a serial device path, optionally :BAUD
    if re.fullmatch(r"COM\d+", scheme, re.IGNORECASE) or rest.isdigit():
        return None  # COM3:57600, ttyUSB0:57600
    close = difflib.get_close_matches(scheme.lower(), [*NETWORK_SCHEMES, "serial"], n=1)
    hint = f"; did you mean {close[0]}:?" if close else ""
    known = ", ".join(f"{s}:" for s in (*NETWORK_SCHEMES, "serial"))
    return f"unknown link scheme {scheme!r}{hint} (known: {known} or a device path)"


class MavlinkEntry(PluginSettings):
    """The kind-specific keys of a mavlink performer entry."""

    vehicle: str | None = Field(None, pattern=r"\S")
    """The vehicle's PDDL object (default: the performer's name)."""
    double: DoubleSettings | None = None
    url: str | None = Field(None, validate_default=True)
    """The link: tcp:HOST:PORT, udpin:..., serial:... (or ``double`` instead)."""
    model: Model | None = None
    commands: dict[str, CommandSettings] = Field(default_factory=dict)
    locations: str | dict[str, Any] | None = None
    """A locations file or the mapping itself (:mod:`.locations`)."""
    cruise_altitude: float = Field(10.0, gt=0)
    arrival_radius: float = Field(1.0, gt=0)
    altitude_tolerance: float = Field(0.5, gt=0)
    resend_period: float = Field(1.0, gt=0)
    feedback_period: float = Field(0.2, gt=0)
    timeouts: Timeouts = Field(default_factory=Timeouts)
    telemetry: TelemetrySettings = Field(default_factory=TelemetrySettings)
    telemetry_hz: dict[str, Annotated[float, Field(gt=0)]] | None = None
    """MAVLink message name -> rate in Hz the vehicle is asked to stream it at."""
    safe_mode: str | None = None
    """Mode for a vehicle still in GUIDED after a failed action or at the end
    (copter LAND, RTL, BRAKE, ...; rover HOLD, ...); None: the model's default."""
    disarm_on_stop: bool = True
    """Disarm a vehicle left armed on the ground when the performer stops."""

    @field_validator("url")
    @classmethod
    def _one_link(cls, value: str | None, info: ValidationInfo) -> str | None:
        if (value is None) == (info.data.get("double") is None):
            raise ValueError(
                "give exactly one of url (tcp:HOST:PORT, udpin:..., serial:...) "
                "and double ({model: copter})"
            )
        if value is not None:
            value = value.strip()
            problem = (
                url_problem(value) if value else "must be a MAVLink URL like tcp:127.0.0.1:5760"
            )
            if problem:
                raise ValueError(f"{value}: {problem}" if value else problem)
        return value

    @field_validator("safe_mode")
    @classmethod
    def _known_mode(cls, value: str | None, info: ValidationInfo) -> str | None:
        if value is None:
            return None
        model = info.data.get("model")
        models: tuple[Model, ...] = (model,) if model is not None else ("copter", "rover")
        allowed = sorted({m for each in models for m in SAFE_MODES[each]})
        if value.upper() not in allowed:
            raise ValueError(f"must be one of {', '.join(allowed)}, got {value!r}")
        return value.upper()


@dataclass(frozen=True)
class MavlinkSettings:
    """What the performer runs with: :class:`MavlinkEntry` with the vehicle named and
    the locations loaded."""

    vehicle: str
    url: str | None = None
    double: Mapping[str, Any] | None = None
    model: Model | None = None
    commands: Mapping[str, Command] = field(default_factory=dict)
    locations: LocationMap | None = None
    cruise_altitude: float = 10.0
    arrival_radius: float = 1.0
    altitude_tolerance: float = 0.5
    resend_period: float = 1.0
    feedback_period: float = 0.2
    timeouts: Timeouts = field(default_factory=Timeouts)
    telemetry: TelemetryConfig = field(default_factory=TelemetryConfig)
    telemetry_hz: Mapping[str, float] = field(default_factory=lambda: dict(DEFAULT_TELEMETRY_HZ))
    safe_mode: str | None = None
    disarm_on_stop: bool = True


def default_command(action: str) -> Command:
    """What an action does when ``commands`` does not say: by name, else a go-to."""
    name = action.lower()
    if name in ("takeoff", "take_off", "take-off"):
        return Command("takeoff")
    if name in ("land", "rtl", "hold"):
        return Command(name)
    if name in ("return_to_launch", "return-to-launch", "return_home"):
        return Command("rtl")
    return Command("goto")


def resolve(entry: MavlinkEntry, name: str, base_dir: Path, key: str) -> MavlinkSettings:
    """The performer's settings from its validated entry: files loaded, names
    normalised (PDDL names lower case, MAVLink message names upper case)."""
    double = None
    if entry.double is not None:
        double = entry.double.model_dump(exclude_none=True)
    telemetry = entry.telemetry.model_dump()
    for fluent in ("battery_function", "low_battery_predicate"):
        if telemetry[fluent] is not None:
            telemetry[fluent] = telemetry[fluent].strip().lower()
    hz = entry.telemetry_hz
    return MavlinkSettings(
        vehicle=(entry.vehicle or name).strip().lower(),
        url=entry.url,
        double=double,
        model=entry.model,
        commands={a.lower(): Command(**c.model_dump()) for a, c in entry.commands.items()},
        locations=(
            None
            if entry.locations is None
            else load_locations(entry.locations, base_dir, f"{key}.locations")
        ),
        cruise_altitude=entry.cruise_altitude,
        arrival_radius=entry.arrival_radius,
        altitude_tolerance=entry.altitude_tolerance,
        resend_period=entry.resend_period,
        feedback_period=entry.feedback_period,
        timeouts=entry.timeouts,
        telemetry=TelemetryConfig(**telemetry),
        telemetry_hz=dict(DEFAULT_TELEMETRY_HZ)
        if hz is None
        else {m.upper(): r for m, r in hz.items()},
        safe_mode=entry.safe_mode,
        disarm_on_stop=entry.disarm_on_stop,
    )


def specialise(
    actions: Mapping[str, tuple[str, ...]], settings: MavlinkSettings, key: str
) -> dict[str, tuple[str, ...]]:
    """Put the vehicle's PDDL name at each command's ``vehicle_arg`` position; every
    command must be for an action the performer serves."""
    unknown = set(settings.commands) - set(actions)
    if unknown:
        raise ConfigError(
            f"commands for actions not listed in actions: {', '.join(sorted(unknown))}",
            key=f"{key}.commands",
        )
    out: dict[str, tuple[str, ...]] = {}
    for action, spec in actions.items():
        args = list(spec)
        cmd = settings.commands.get(action)
        if cmd is not None and cmd.vehicle_arg is not None:
            i = cmd.vehicle_arg
            args += [""] * (i + 1 - len(args))
            if args[i] not in ("", settings.vehicle):
                raise ConfigError(
                    f"argument {i} is the vehicle ({settings.vehicle}) but actions.{action} "
                    f"specialises it to {args[i]!r}",
                    key=f"{key}.commands.{action}.vehicle_arg",
                )
            args[i] = settings.vehicle
        out[action] = tuple(args)
    return out
