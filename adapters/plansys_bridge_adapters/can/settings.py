"""The CAN performer's mission-file settings, checked up front with precise keys.

A performer entry looks like::

    - kind: can
      name: base_r2d2
      robot: r2d2                       # the PDDL object this base is
      actions:
        move: {robot: 0, destination: 2}  # (move ?robot ?from ?to)
      locations: can_locations.yaml     # or an inline mapping
      bus: {interface: virtual, channel: plansys_can0}
      controller: {max_linear: 0.5, goal_tolerance: 0.05}
      safety: {heartbeat_timeout: 0.5}
      battery: {function: battery, low_predicate: battery_low, low_below: 20}
      simulate_base: {x: 0.0, y: 0.0}   # virtual bus only: run the base double
      record_topic: /r2d2/pose          # odometry into the mission bag (every record_period)

Every mistake is a :class:`ConfigError` naming its key (``performers[1].safety.
heartbeat_timeout``) and, for the locations file, the file.
"""

from __future__ import annotations

import dataclasses
import math
import types
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar, Union, get_args, get_origin, get_type_hints

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission_config import load_yaml_file

from .bus import BusConfig, choose_interface
from .controller import ControllerConfig, MotionLimits
from .double import BaseDoubleConfig, BaseLimits
from .replay import ReplaySettings, parse_replay

T = TypeVar("T")


@dataclass(frozen=True)
class Location:
    """A named place in the base's odom frame; ``via`` points are driven through in order."""

    name: str
    x: float
    y: float
    yaw: float | None = None
    via: tuple[tuple[float, float], ...] = ()


@dataclass(frozen=True)
class MotionAction:
    """Which arguments of a PDDL action are the robot and the destination (0-based)."""

    robot_arg: int | None
    destination_arg: int


@dataclass(frozen=True)
class SafetySettings:
    command_rate: float = 20.0
    """Velocity commands per second while an action runs (keeps the base's watchdog fed)."""
    heartbeat_timeout: float = 0.5
    """No BASE_Status with a new alive counter for this long = heartbeat lost."""
    odometry_timeout: float = 0.3
    startup_timeout: float = 2.0
    """How long an action waits for fresh odometry and status before failing."""
    stop_timeout: float = 3.0
    """How long a cancel/arrival waits for the measured twist to confirm standstill."""
    stopped_linear: float = 0.01
    stopped_angular: float = 0.02
    stall_timeout: float = 10.0
    """Commanded to move but the pose has not changed for this long = stalled."""
    max_duration: float | None = None
    error_frame_limit: int = 1
    """CAN error frames during one action that end it (1: the first one does)."""
    estop_on_stop_failure: bool = True
    """Engage the e-stop when a cancel cannot confirm that the base stopped."""


@dataclass(frozen=True)
class BatterySettings:
    """Write the status frame's battery into the knowledge base."""

    function: str | None = "battery"
    """Numeric fluent set as ``(= (<function> <robot>) <percent>)``; null to skip."""
    low_predicate: str | None = None
    """Predicate ``(<low_predicate> <robot>)`` added below ``low_below`` percent."""
    low_below: float = 20.0
    hysteresis: float = 2.0
    """The low predicate is removed again only above ``low_below + hysteresis``."""
    min_change: float = 1.0
    """Percent change before the fluent is written again (keeps the knowledge calm)."""


@dataclass(frozen=True)
class CanBaseSettings:
    robot: str
    motions: dict[str, MotionAction]
    locations: dict[str, Location]
    bus: BusConfig = field(default_factory=BusConfig)
    dbc: Path | None = None
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    safety: SafetySettings = field(default_factory=SafetySettings)
    battery: BatterySettings | None = None
    simulate_base: BaseDoubleConfig | None = None
    replay: ReplaySettings | None = None
    """A recorded log played on the virtual bus in place of the base (:mod:`.replay`)."""
    feedback_period: float = 0.2
    record_topic: str = ""
    """Bag topic of the odometry pose when the mission is recorded ("": /<robot>/pose)."""
    record_period: float = 0.1


def _type_ok(value: object, hint: object) -> bool:
    origin = get_origin(hint)
    if origin in (Union, types.UnionType):
        return any(_type_ok(value, arg) for arg in get_args(hint))
    if hint is type(None):
        return value is None
    if hint is bool:
        return isinstance(value, bool)
    if hint is float:
        return isinstance(value, int | float) and not isinstance(value, bool)
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if hint is str:
        return isinstance(value, str)
    return False


def parse_dataclass(cls: type[T], value: object, key: str, **fixed: Any) -> T:
    """Build a flat dataclass of numbers/bools/strings from a mapping, naming bad keys.

    Numbers must be finite and, unless the field is a signed angle or position,
    not negative.
    """
    if value is None:
        value = {}
    if not isinstance(value, Mapping):
        raise ConfigError(f"must be a mapping, got {value!r}", key=key)
    hints = get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]  # type: ignore[arg-type]
    kwargs: dict[str, Any] = dict(fixed)
    for name, item in value.items():
        where = f"{key}.{name}"
        if name not in names or name in fixed:
            allowed = ", ".join(n for n in names if n not in fixed)
            raise ConfigError(f"unknown key (allowed: {allowed})", key=where)
        hint = hints[name]
        if not _type_ok(item, hint):
            raise ConfigError(f"expected {_hint_text(hint)}, got {item!r}", key=where)
        if isinstance(item, int | float) and not isinstance(item, bool):
            if not math.isfinite(item):
                raise ConfigError(f"must be finite, got {item!r}", key=where)
            if item < 0 and name not in _SIGNED:
                raise ConfigError(f"must not be negative, got {item!r}", key=where)
            if _accepts_float(hint):
                item = float(item)
        kwargs[name] = item
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise ConfigError(str(exc), key=key) from exc


_SIGNED = frozenset({"x", "y", "yaw"})


def _accepts_float(hint: object) -> bool:
    return hint is float or float in get_args(hint)


def _hint_text(hint: object) -> str:
    if get_origin(hint) in (Union, types.UnionType):
        return " or ".join(_hint_text(a) for a in get_args(hint))
    if hint is type(None):
        return "null"
    return {float: "a number", int: "an integer", bool: "true/false", str: "a string"}.get(
        hint,
        str(hint),  # type: ignore[call-overload]
    )


def _number(value: object, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"must be a number, got {value!r}", key=key)
    return float(value)


def parse_location(name: str, value: object, key: str) -> Location:
    """``{x, y, yaw?, via?}`` or ``[x, y]`` / ``[x, y, yaw]``."""
    if isinstance(value, list | tuple):
        if len(value) not in (2, 3):
            raise ConfigError(f"must be [x, y] or [x, y, yaw], got {value!r}", key=key)
        nums = [_number(v, f"{key}[{i}]") for i, v in enumerate(value)]
        return Location(name, nums[0], nums[1], nums[2] if len(nums) == 3 else None)
    if not isinstance(value, Mapping):
        raise ConfigError(f"must be {{x, y, yaw}} or [x, y, yaw], got {value!r}", key=key)
    for item in value:
        if item not in ("x", "y", "yaw", "via"):
            raise ConfigError("unknown key (allowed: x, y, yaw, via)", key=f"{key}.{item}")
    for item in ("x", "y"):
        if item not in value:
            raise ConfigError("missing", key=f"{key}.{item}")
    yaw = value.get("yaw")
    via_value = value.get("via") or []
    if not isinstance(via_value, list | tuple):
        raise ConfigError(f"must be a list of [x, y] points, got {via_value!r}", key=f"{key}.via")
    via: list[tuple[float, float]] = []
    for i, point in enumerate(via_value):
        where = f"{key}.via[{i}]"
        if not isinstance(point, list | tuple) or len(point) != 2:
            raise ConfigError(f"must be [x, y], got {point!r}", key=where)
        via.append((_number(point[0], f"{where}[0]"), _number(point[1], f"{where}[1]")))
    return Location(
        name,
        _number(value["x"], f"{key}.x"),
        _number(value["y"], f"{key}.y"),
        None if yaw is None else _number(yaw, f"{key}.yaw"),
        tuple(via),
    )


def load_locations(value: object, base_dir: Path, key: str) -> dict[str, Location]:
    """Locations inline (a mapping) or from a YAML file with a ``locations:`` mapping."""
    file: str | None = None
    if isinstance(value, str | Path):
        path = Path(value)
        if not path.is_absolute():
            path = base_dir / path
        file = str(path)
        loaded = load_yaml_file(path, "locations file", key)
        if not isinstance(loaded, Mapping) or "locations" not in loaded:
            raise ConfigError("needs a top-level 'locations:' mapping", key="locations", file=file)
        value = loaded["locations"]
        key = "locations"
    if not isinstance(value, Mapping) or not value:
        raise ConfigError("must map location names to {x, y, yaw}", key=key, file=file)
    out: dict[str, Location] = {}
    for name, spec in value.items():
        if not isinstance(name, str) or not name.strip():
            raise ConfigError(f"location names must be strings, got {name!r}", key=key, file=file)
        lowered = name.strip().lower()
        try:
            out[lowered] = parse_location(lowered, spec, f"{key}.{name}")
        except ConfigError as exc:
            if file is None:
                raise
            raise ConfigError(str(exc).split(": ", 1)[-1], key=exc.key, file=file) from exc
    return out


def parse_motions(
    value: object, robot: str, key: str
) -> tuple[dict[str, tuple[str, ...]], dict[str, MotionAction]]:
    """``actions`` for a base: ``{move: {robot: 0, destination: 2}}`` or the list form.

    Returns the specialised arguments the framework matches on (the robot's own
    name at the robot position) and which argument is the destination. With the list
    form (``move: [r2d2, "", ""]``) the robot is where the robot's name is and the
    destination is the last argument.
    """
    if not isinstance(value, Mapping) or not value:
        raise ConfigError(
            "must map each move action to {robot: <index>, destination: <index>}", key=key
        )
    specs: dict[str, tuple[str, ...]] = {}
    motions: dict[str, MotionAction] = {}
    for action, spec in value.items():
        if not isinstance(action, str) or not action.strip():
            raise ConfigError(f"action names must be strings, got {action!r}", key=key)
        name = action.strip().lower()
        where = f"{key}.{action}"
        if isinstance(spec, Mapping):
            for item in spec:
                if item not in ("robot", "destination"):
                    raise ConfigError(
                        "unknown key (allowed: robot, destination)", key=f"{where}.{item}"
                    )
            robot_arg = spec.get("robot")
            dest_arg = spec.get("destination")
            for item, index in (("robot", robot_arg), ("destination", dest_arg)):
                if index is None and item == "robot":
                    continue
                if isinstance(index, bool) or not isinstance(index, int) or index < 0:
                    raise ConfigError(
                        f"must be a 0-based argument index, got {index!r}", key=f"{where}.{item}"
                    )
            assert isinstance(dest_arg, int)
            if robot_arg == dest_arg:
                raise ConfigError("robot and destination are the same argument", key=where)
            size = max(dest_arg, robot_arg if robot_arg is not None else 0) + 1
            args = [""] * size
            if robot_arg is not None:
                args[robot_arg] = robot
            specs[name] = tuple(args)
            motions[name] = MotionAction(robot_arg, dest_arg)
        elif isinstance(spec, list | tuple) and spec:
            args = ["" if a is None else str(a).strip().lower() for a in spec]
            robot_index = args.index(robot) if robot in args else None
            if robot_index == len(args) - 1:
                raise ConfigError("the last argument (destination) is the robot", key=where)
            specs[name] = tuple(args)
            motions[name] = MotionAction(robot_index, len(args) - 1)
        else:
            raise ConfigError(
                f"must be {{robot: <index>, destination: <index>}} or a list of specialised "
                f"arguments, got {spec!r}",
                key=where,
            )
    return specs, motions


def parse_controller(value: object, key: str) -> ControllerConfig:
    """Controller gains and limits in one flat mapping."""
    if value is None:
        return ControllerConfig()
    if not isinstance(value, Mapping):
        raise ConfigError(f"must be a mapping, got {value!r}", key=key)
    limit_names = {f.name for f in dataclasses.fields(MotionLimits)}
    limits = parse_dataclass(
        MotionLimits, {k: v for k, v in value.items() if k in limit_names}, key
    )
    rest = {k: v for k, v in value.items() if k not in limit_names}
    try:
        return parse_dataclass(ControllerConfig, rest, key, limits=limits)
    except ConfigError as exc:
        if "unknown key" in str(exc):
            allowed = sorted(
                limit_names | {f.name for f in dataclasses.fields(ControllerConfig)} - {"limits"}
            )
            raise ConfigError(f"unknown key (allowed: {', '.join(allowed)})", key=exc.key) from exc
        raise


def parse_bus(value: object, key: str, *, simulated: bool = False) -> BusConfig:
    if value is None:
        value = {}
    if not isinstance(value, Mapping):
        raise ConfigError(f"must be a mapping, got {value!r}", key=key)
    allowed = (
        "interface",
        "channel",
        "bitrate",
        "reader",
        "poll_period",
        "send_timeout",
        "reopen_period",
        "options",
    )
    for item in value:
        if item not in allowed:
            raise ConfigError(f"unknown key (allowed: {', '.join(allowed)})", key=f"{key}.{item}")
    interface = value.get("interface")
    channel = value.get("channel")
    if interface is not None and (not isinstance(interface, str) or not interface):
        raise ConfigError(
            f"must be a python-can interface name, got {interface!r}", key=f"{key}.interface"
        )
    if channel is not None and (not isinstance(channel, str | int) or isinstance(channel, bool)):
        raise ConfigError(f"must be a channel name, got {channel!r}", key=f"{key}.channel")
    bitrate = value.get("bitrate")
    if bitrate is not None and (
        isinstance(bitrate, bool) or not isinstance(bitrate, int) or bitrate <= 0
    ):
        raise ConfigError(f"must be a positive integer, got {bitrate!r}", key=f"{key}.bitrate")
    reader = value.get("reader", "auto")
    if reader not in ("auto", "notifier", "poll"):
        raise ConfigError(f"must be auto, notifier or poll, got {reader!r}", key=f"{key}.reader")
    options = value.get("options") or {}
    if not isinstance(options, Mapping):
        raise ConfigError(f"must be a mapping, got {options!r}", key=f"{key}.options")
    timing = {
        name: _positive(value.get(name, default), f"{key}.{name}")
        for name, default in (("poll_period", 0.005), ("send_timeout", 0.05))
    }
    reopen = value.get("reopen_period", 1.0)
    reopen_period = None if reopen is None else _positive(reopen, f"{key}.reopen_period")
    try:
        interface, channel, origin = choose_interface(
            interface, None if channel is None else str(channel), simulated=simulated
        )
    except ValueError as exc:
        raise ConfigError(str(exc), key=f"{key}.interface") from exc
    return BusConfig(
        interface=interface,
        reopen_period=reopen_period,
        channel=str(channel),
        bitrate=bitrate,
        reader=reader,
        options=dict(options),
        origin=origin,
        **timing,
    )


def _positive(value: object, key: str) -> float:
    number = _number(value, key)
    if number <= 0:
        raise ConfigError(f"must be > 0, got {value!r}", key=key)
    return number


def parse_simulated_base(value: object, bus: BusConfig, key: str) -> BaseDoubleConfig | None:
    if value is None or value is False:
        return None
    if bus.interface != "virtual":
        raise ConfigError(
            f"the simulated base runs only on the 'virtual' interface, not {bus.interface!r}; "
            "remove simulate_base to drive a real base",
            key=key,
        )
    if value is True:
        return BaseDoubleConfig()
    if not isinstance(value, Mapping):
        raise ConfigError(f"must be true or a mapping, got {value!r}", key=key)
    limit_names = {f.name for f in dataclasses.fields(BaseLimits)}
    limits = parse_dataclass(BaseLimits, {k: v for k, v in value.items() if k in limit_names}, key)
    rest = {k: v for k, v in value.items() if k not in limit_names}
    return parse_dataclass(BaseDoubleConfig, rest, key, limits=limits)


def _replay(value: object, bus: BusConfig, base_dir: Path, key: str) -> ReplaySettings | None:
    if value not in (None, False) and bus.interface != "virtual":
        raise ConfigError(
            f"a recorded log is replayed on the 'virtual' interface, not {bus.interface!r}",
            key=key,
        )
    return parse_replay(value, base_dir, key)


def parse_settings(
    settings: Mapping[str, Any], actions: object, base_dir: Path, key: str
) -> tuple[CanBaseSettings, dict[str, tuple[str, ...]]]:
    """Check a CAN performer entry's kind-specific keys; returns settings and action specs."""
    robot = settings.get("robot")
    if not isinstance(robot, str) or not robot.strip():
        raise ConfigError("the PDDL object this base is (a non-empty string)", key=f"{key}.robot")
    robot = robot.strip().lower()
    specs, motions = parse_motions(actions, robot, f"{key}.actions")
    if "locations" not in settings:
        raise ConfigError("missing: a locations file or mapping", key=f"{key}.locations")
    locations = load_locations(settings["locations"], base_dir, f"{key}.locations")
    replay = settings.get("replay") not in (None, False)
    if replay and settings.get("simulate_base") not in (None, False):
        raise ConfigError("a base is either simulated or replayed, not both", key=f"{key}.replay")
    simulated = replay or settings.get("simulate_base") not in (None, False)
    bus = parse_bus(settings.get("bus"), f"{key}.bus", simulated=simulated)
    dbc_value = settings.get("dbc")
    dbc: Path | None = None
    if dbc_value is not None:
        if not isinstance(dbc_value, str):
            raise ConfigError(f"must be a path, got {dbc_value!r}", key=f"{key}.dbc")
        dbc = Path(dbc_value) if Path(dbc_value).is_absolute() else base_dir / dbc_value
    battery_value = settings.get("battery")
    battery = (
        None
        if battery_value is None or battery_value is False
        else parse_dataclass(
            BatterySettings, {} if battery_value is True else battery_value, f"{key}.battery"
        )
    )
    feedback = _positive(settings.get("feedback_period", 0.2), f"{key}.feedback_period")
    record_period = _positive(settings.get("record_period", 0.1), f"{key}.record_period")
    record_topic = settings.get("record_topic") or f"/{robot}/pose"
    if not isinstance(record_topic, str) or not record_topic.startswith("/"):
        raise ConfigError(
            f"must be a topic name starting with '/', got {record_topic!r}",
            key=f"{key}.record_topic",
        )
    parsed = CanBaseSettings(
        robot=robot,
        motions=motions,
        locations=locations,
        bus=bus,
        dbc=dbc,
        controller=parse_controller(settings.get("controller"), f"{key}.controller"),
        safety=parse_dataclass(SafetySettings, settings.get("safety"), f"{key}.safety"),
        battery=battery,
        simulate_base=parse_simulated_base(
            settings.get("simulate_base"), bus, f"{key}.simulate_base"
        ),
        replay=_replay(settings.get("replay"), bus, base_dir, f"{key}.replay"),
        feedback_period=feedback,
        record_topic=record_topic,
        record_period=record_period,
    )
    return parsed, specs
