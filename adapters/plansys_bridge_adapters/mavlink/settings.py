"""The kind-specific keys of a ``kind: mavlink`` performer entry, checked.

Every mistake is a :class:`ConfigError` naming its key (``performers[1].commands.fly.do``)
before any link is opened.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from plansys_bridge.errors import ConfigError

from ..checks import mapping, positive
from .locations import LocationMap, load_locations
from .modes import Model
from .safety import SAFE_MODES
from .telemetry import TelemetryConfig
from .vehicle import DEFAULT_TELEMETRY_HZ

SETTINGS_KEYS = frozenset(
    {
        "url",
        "double",
        "vehicle",
        "model",
        "commands",
        "locations",
        "cruise_altitude",
        "arrival_radius",
        "altitude_tolerance",
        "resend_period",
        "feedback_period",
        "timeouts",
        "telemetry",
        "telemetry_hz",
        "safe_mode",
        "disarm_on_stop",
    }
)
DOES = ("takeoff", "goto", "land", "rtl", "hold")
_COMMAND_KEYS = frozenset({"do", "vehicle_arg", "target_arg", "altitude", "seconds", "takeoff"})
_DOUBLE_KEYS = frozenset(
    {
        "model",
        "speedup",
        "transport",
        "ekf_delay",
        "home",
        "disarm_delay",
        "cruise_speed",
        "battery_failsafe_pct",
        "battery_capacity_s",
        "position_modes_need_ekf",
    }
)
_TIMEOUT_KEYS = frozenset({"connect", "heartbeat", "command", "ekf", "arm", "action", "stall"})


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


@dataclass(frozen=True)
class Timeouts:
    """Seconds (wall clock): link, heartbeat loss, COMMAND_ACK, EKF, arming, one action."""

    connect: float = 30.0
    heartbeat: float = 3.0
    command: float = 1.0
    ekf: float = 120.0
    arm: float = 30.0
    action: float = 600.0
    stall: float = 20.0
    """Seconds of the vehicle's own time a go-to may go without getting closer."""


@dataclass(frozen=True)
class MavlinkSettings:
    """The kind-specific keys of a mavlink performer entry, checked."""

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
    """Mode for a vehicle still in GUIDED after a failed action or at the end
    (copter LAND, RTL, BRAKE, ...; rover HOLD, ...); None: the model's default."""
    disarm_on_stop: bool = True
    """Disarm a vehicle left armed on the ground when the performer stops."""


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


def specialise(
    actions: Mapping[str, tuple[str, ...]], settings: MavlinkSettings, key: str
) -> dict[str, tuple[str, ...]]:
    """Put the vehicle's PDDL name at each command's ``vehicle_arg`` position."""
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


def parse_settings(raw: Mapping[str, Any], name: str, base_dir: Path, key: str) -> MavlinkSettings:
    """Check the kind-specific keys; every error names its key."""
    values: dict[str, Any] = {}
    vehicle = raw.get("vehicle", name)
    if not isinstance(vehicle, str) or not vehicle.strip():
        raise ConfigError(
            f"must be the vehicle's PDDL object name, got {vehicle!r}", key=f"{key}.vehicle"
        )
    values["vehicle"] = vehicle.strip().lower()
    url, double = raw.get("url"), raw.get("double")
    if (url is None) == (double is None):
        raise ConfigError(
            "give exactly one of url (tcp:HOST:PORT, udpin:..., serial:...) "
            "and double ({model: copter})",
            key=f"{key}.url",
        )
    if url is not None:
        if not isinstance(url, str) or not url.strip():
            raise ConfigError(
                f"must be a MAVLink URL like tcp:127.0.0.1:5760, got {url!r}", key=f"{key}.url"
            )
        values["url"] = url.strip()
        problem = url_problem(values["url"])
        if problem:
            raise ConfigError(f"{values['url']}: {problem}", key=f"{key}.url")
    if double is not None:
        values["double"] = _double(double, f"{key}.double")
    model = raw.get("model")
    if model is not None:
        if model not in ("copter", "rover"):
            raise ConfigError(f"must be copter or rover, got {model!r}", key=f"{key}.model")
        values["model"] = model
    commands = raw.get("commands") or {}
    if not isinstance(commands, Mapping):
        raise ConfigError("must map action names to {do: ...}", key=f"{key}.commands")
    values["commands"] = {
        str(a).lower(): _command(c, f"{key}.commands.{a}") for a, c in commands.items()
    }
    if raw.get("locations") is not None:
        spec = raw["locations"]
        if not isinstance(spec, str | Mapping):
            raise ConfigError("must be a file name or a mapping", key=f"{key}.locations")
        values["locations"] = load_locations(spec, base_dir, f"{key}.locations")
    for name_ in (
        "cruise_altitude",
        "arrival_radius",
        "altitude_tolerance",
        "resend_period",
        "feedback_period",
    ):
        if name_ in raw:
            values[name_] = positive(raw[name_], f"{key}.{name_}")
    timeouts = mapping(
        raw.get("timeouts") or {},
        f"{key}.timeouts",
        _TIMEOUT_KEYS,
        "must be a mapping of seconds, e.g. {ekf: 120}",
    )
    values["timeouts"] = Timeouts(
        **{t: positive(v, f"{key}.timeouts.{t}") for t, v in timeouts.items()}
    )
    values["telemetry"] = TelemetryConfig.from_mapping(raw.get("telemetry"), f"{key}.telemetry")
    if raw.get("telemetry_hz") is not None:
        hz = raw["telemetry_hz"]
        if not isinstance(hz, Mapping):
            raise ConfigError(
                "must map MAVLink message names to rates in Hz", key=f"{key}.telemetry_hz"
            )
        values["telemetry_hz"] = {
            str(m).upper(): positive(r, f"{key}.telemetry_hz.{m}") for m, r in hz.items()
        }
    if raw.get("safe_mode") is not None:
        values["safe_mode"] = _safe_mode(raw["safe_mode"], values.get("model"), f"{key}.safe_mode")
    if "disarm_on_stop" in raw:
        flag = raw["disarm_on_stop"]
        if not isinstance(flag, bool):
            raise ConfigError(f"must be true or false, got {flag!r}", key=f"{key}.disarm_on_stop")
        values["disarm_on_stop"] = flag
    return MavlinkSettings(**values)


def _safe_mode(value: object, model: Model | None, key: str) -> str:
    models: tuple[Model, ...] = (model,) if model is not None else ("copter", "rover")
    allowed = sorted({m for each in models for m in SAFE_MODES[each]})
    name = value.upper() if isinstance(value, str) else value
    if name not in allowed:
        raise ConfigError(f"must be one of {', '.join(allowed)}, got {value!r}", key=key)
    return str(name)


def _command(value: object, key: str) -> Command:
    if isinstance(value, str):
        value = {"do": value}
    value = mapping(value, key, _COMMAND_KEYS, f"must be {{do: one of {', '.join(DOES)}, ...}}")
    do = value.get("do")
    if do not in DOES:
        raise ConfigError(f"must be one of {', '.join(DOES)}, got {do!r}", key=f"{key}.do")
    fields: dict[str, Any] = {"do": do}
    for k in ("vehicle_arg", "target_arg"):
        if k in value:
            v = value[k]
            if isinstance(v, bool) or not isinstance(v, int) or (k == "vehicle_arg" and v < 0):
                raise ConfigError(
                    f"must be an argument position (0 = first), got {v!r}", key=f"{key}.{k}"
                )
            fields[k] = v
    for k in ("altitude", "seconds"):
        if k in value:
            fields[k] = positive(value[k], f"{key}.{k}")
    if "takeoff" in value:
        if not isinstance(value["takeoff"], bool) or do != "goto":
            raise ConfigError(
                f"must be true or false, on a goto command, got {value['takeoff']!r}",
                key=f"{key}.takeoff",
            )
        fields["takeoff"] = value["takeoff"]
    return Command(**fields)


def _double(value: object, key: str) -> dict[str, Any]:
    hint = "must be a mapping like {model: copter, speedup: 5}"
    out = dict(mapping(value, key, _DOUBLE_KEYS, hint))
    if out.get("model", "copter") not in ("copter", "rover"):
        raise ConfigError(f"must be copter or rover, got {out['model']!r}", key=f"{key}.model")
    for k in ("speedup", "ekf_delay", "disarm_delay", "cruise_speed", "battery_capacity_s"):
        if k in out:
            out[k] = positive(out[k], f"{key}.{k}")
    if "home" in out:
        home = out["home"]
        if not isinstance(home, Mapping) or "lat" not in home or "lon" not in home:
            raise ConfigError("must be {lat: .., lon: .., alt: ..}", key=f"{key}.home")
    return out
