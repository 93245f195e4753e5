"""The CAN performer's mission-file settings, as the pydantic model the mission loads.

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

:class:`CanSettings` is validated when the mission loads (every mistake names its
key, line and column); :func:`resolve` then loads the locations file, picks the bus
through python-can's configuration chain and gives the performer its
:class:`CanBaseSettings`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal, TypeVar, get_type_hints

from pydantic import Field, ValidationInfo, create_model, field_validator, model_validator

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.plugins import PluginSettings, validate_settings
from plansys_bridge.yaml_files import load_yaml_document

from .bus import BusConfig, check_known_interface, choose_interface
from .controller import ControllerConfig, MotionLimits
from .dbc import MobileBaseDbc
from .double import BaseDoubleConfig, BaseLimits
from .replay import ReplaySettings, parse_replay

D = TypeVar("D")


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


class SafetySettings(PluginSettings):
    command_rate: float = Field(20.0, ge=0)
    """Velocity commands per second while an action runs (keeps the base's watchdog fed)."""
    heartbeat_timeout: float = Field(0.5, ge=0)
    """No BASE_Status with a new alive counter for this long = heartbeat lost."""
    odometry_timeout: float = Field(0.3, ge=0)
    startup_timeout: float = Field(2.0, ge=0)
    """How long an action waits for fresh odometry and status before failing."""
    stop_timeout: float = Field(3.0, ge=0)
    """How long a cancel/arrival waits for the measured twist to confirm standstill."""
    stopped_linear: float = Field(0.01, ge=0)
    stopped_angular: float = Field(0.02, ge=0)
    stall_timeout: float = Field(10.0, ge=0)
    """Commanded to move but the pose has not changed for this long = stalled."""
    max_duration: float | None = Field(None, ge=0)
    error_frame_limit: int = Field(1, ge=0)
    """CAN error frames during one action that end it (1: the first one does)."""
    estop_on_stop_failure: bool = True
    """Engage the e-stop when a cancel cannot confirm that the base stopped."""


class BatterySettings(PluginSettings):
    """Write the status frame's battery into the knowledge base."""

    function: str | None = "battery"
    """Numeric fluent set as ``(= (<function> <robot>) <percent>)``; null to skip."""
    low_predicate: str | None = None
    """Predicate ``(<low_predicate> <robot>)`` added below ``low_below`` percent."""
    low_below: float = Field(20.0, ge=0)
    hysteresis: float = Field(2.0, ge=0)
    """The low predicate is removed again only above ``low_below + hysteresis``."""
    min_change: float = Field(1.0, ge=0)
    """Percent change before the fluent is written again (keeps the knowledge calm)."""


def _flat_model(name: str, *classes: type, signed: frozenset[str] = frozenset()) -> Any:
    """A settings model with the fields of ``classes`` (dataclasses) in one flat
    mapping, as the mission file gives them: numbers finite and, unless ``signed``,
    not negative (the dataclasses check what must be > 0)."""
    fields: dict[str, Any] = {}
    for cls in classes:
        hints = get_type_hints(cls)
        for f in dataclasses.fields(cls):
            if f.name == "limits" or f.name in fields:
                continue
            numeric = hints[f.name] in (float, int, float | None, int | None)
            bound: dict[str, Any] = {"ge": 0} if numeric and f.name not in signed else {}
            fields[f.name] = (hints[f.name], Field(f.default, **bound))
    return create_model(name, __base__=PluginSettings, **fields)


ControllerSettings = _flat_model("ControllerSettings", ControllerConfig, MotionLimits)
"""``controller:`` gains and limits (:class:`ControllerConfig`, :class:`MotionLimits`)."""
SimulatedBaseSettings = _flat_model(
    "SimulatedBaseSettings", BaseDoubleConfig, BaseLimits, signed=frozenset({"x", "y", "yaw"})
)
"""``simulate_base:`` the double's start pose, physics and limits."""


def _split(values: Any, outer: Callable[..., D], inner: type, key: str) -> D:
    """``outer(**rest, limits=inner(**its fields))`` from a flat settings model."""
    data = values.model_dump()
    names = {f.name for f in dataclasses.fields(inner)}
    try:
        limits = inner(**{k: v for k, v in data.items() if k in names})
        return outer(**{k: v for k, v in data.items() if k not in names}, limits=limits)
    except ValueError as exc:
        raise ConfigError(str(exc), key=key) from exc


def _true_is_empty(value: object) -> object:
    """``battery: true`` means the defaults, ``false`` means none."""
    if value is True:
        return {}
    return None if value is False else value


class BusSettings(PluginSettings):
    interface: str | None = Field(None, min_length=1)
    """A python-can interface; without one, python-can's own configuration decides."""
    channel: str | None = None
    bitrate: int | None = Field(None, gt=0)
    reader: Literal["auto", "notifier", "poll"] = "auto"
    poll_period: float = Field(0.005, gt=0)
    send_timeout: float = Field(0.05, gt=0)
    reopen_period: float | None = Field(1.0, gt=0)
    options: dict[str, Any] = Field(default_factory=dict)
    """Extra keyword arguments for :class:`can.Bus`."""

    @field_validator("channel", mode="before")
    @classmethod
    def _channel_number(cls, value: object) -> object:
        return str(value) if isinstance(value, int) and not isinstance(value, bool) else value

    @field_validator("interface")
    @classmethod
    def _known(cls, value: str | None) -> str | None:
        if value is not None:
            check_known_interface(value, "interface")
        return value


class LocationSpec(PluginSettings):
    """``{x, y, yaw?, via?}`` or ``[x, y]`` / ``[x, y, yaw]``."""

    x: float
    y: float
    yaw: float | None = None
    via: list[Annotated[list[float], Field(min_length=2, max_length=2)]] = Field(
        default_factory=list
    )

    @model_validator(mode="before")
    @classmethod
    def _list_form(cls, value: object) -> object:
        if isinstance(value, list | tuple):
            if len(value) not in (2, 3):
                raise ValueError(f"must be [x, y] or [x, y, yaw], got {list(value)!r}")
            return dict(zip(("x", "y", "yaw"), value, strict=False))
        return value


class CanSettings(PluginSettings):
    """The kind-specific keys of a ``kind: can`` performer entry."""

    robot: Annotated[str, Field(min_length=1, pattern=r"\S")]
    """The PDDL object this base is."""
    locations: Annotated[dict[str, LocationSpec], Field(min_length=1)] | str
    """A locations file (``locations:`` mapping, read when the performer is built) or
    the table itself, checked here so a bad entry is an error when the mission loads."""
    bus: BusSettings = Field(default_factory=BusSettings)
    dbc: str | None = None
    controller: ControllerSettings = Field(default_factory=ControllerSettings)  # type: ignore[valid-type]
    safety: SafetySettings = Field(default_factory=SafetySettings)
    battery: BatterySettings | None = None
    simulate_base: SimulatedBaseSettings | None = None  # type: ignore[valid-type]
    feedback_period: float = Field(0.2, gt=0)
    record_topic: str = Field("", pattern=r"^(/.*)?$")
    """Bag topic of the odometry pose when the mission is recorded ("": /<robot>/pose)."""
    record_period: float = Field(0.1, gt=0)
    replay: Any = None
    """A recorded log (``{log, rate, include_tx}`` or its path) played on the virtual
    bus in place of the base (:mod:`.replay`); checked with the log when built."""

    @field_validator("locations", mode="before")
    @classmethod
    def _file_or_table(cls, value: object) -> object:
        """One error for a value that is neither (pydantic would list both branches)."""
        if isinstance(value, str) and not value.strip():
            raise ValueError("must name a locations file or be a mapping of locations")
        if isinstance(value, str):
            return value
        if not isinstance(value, Mapping):
            raise ValueError(
                f"must be a locations file or a mapping of name: [x, y, yaw?], got {value!r}"
            )
        for name in value:
            if not isinstance(name, str) or not name.strip():
                raise ValueError(f"location names must be non-empty strings, got {name!r}")
        return value

    _battery = field_validator("battery", mode="before")(_true_is_empty)
    _simulate = field_validator("simulate_base", mode="before")(_true_is_empty)

    @field_validator("simulate_base")
    @classmethod
    def _double_needs_virtual_bus(cls, value: Any, info: ValidationInfo) -> Any:
        bus = info.data.get("bus")
        interface = bus.interface if isinstance(bus, BusSettings) else None
        if value is not None and interface not in (None, "virtual"):
            raise ValueError(
                f"the simulated base runs only on the 'virtual' interface, not {interface!r}; "
                "remove simulate_base to drive a real base"
            )
        return value


@dataclass(frozen=True)
class CanBaseSettings:
    """What the performer runs with: :class:`CanSettings` with its files loaded and
    the bus chosen."""

    robot: str
    motions: dict[str, MotionAction]
    locations: dict[str, Location]
    bus: BusConfig = dataclasses.field(default_factory=BusConfig)
    dbc: Path | None = None
    controller: ControllerConfig = dataclasses.field(default_factory=ControllerConfig)
    safety: SafetySettings = dataclasses.field(default_factory=SafetySettings)
    battery: BatterySettings | None = None
    simulate_base: BaseDoubleConfig | None = None
    feedback_period: float = 0.2
    record_topic: str = ""
    record_period: float = 0.1
    replay: ReplaySettings | None = None
    """A recorded log played on the virtual bus in place of the base (:mod:`.replay`)."""


class _LocationTable(PluginSettings):
    locations: dict[str, LocationSpec] = Field(min_length=1)


def load_locations(value: object, base_dir: Path, key: str) -> dict[str, Location]:
    """Locations inline (a mapping) or from a YAML file with a ``locations:`` mapping;
    errors in the file name it, with line and column."""
    if isinstance(value, str | Path):
        path = Path(value)
        path = path if path.is_absolute() else base_dir / path
        loaded, positions = load_yaml_document(path, "locations file", key)
        if not isinstance(loaded, Mapping) or "locations" not in loaded:
            raise ConfigError(
                "needs a top-level 'locations:' mapping", key="locations", file=str(path)
            )
        try:
            table = validate_settings(_LocationTable, {"locations": loaded["locations"]})
        except ConfigError as exc:
            raise positions.relocate(exc) from exc
    else:
        prefix = key.rpartition(".")[0] if key.endswith("locations") else key
        table = validate_settings(_LocationTable, {"locations": value}, key=prefix)
    out: dict[str, Location] = {}
    for name, spec in table.locations.items():
        lowered = name.strip().lower()
        via = tuple((p[0], p[1]) for p in spec.via)
        out[lowered] = Location(lowered, spec.x, spec.y, spec.yaw, via)
    return out


class _MotionSpec(PluginSettings):
    robot: int | None = Field(None, ge=0)
    destination: int = Field(ge=0)


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
            motion = validate_settings(_MotionSpec, spec, key=where)
            if motion.robot == motion.destination:
                raise ConfigError("robot and destination are the same argument", key=where)
            args = [""] * (max(motion.destination, motion.robot or 0) + 1)
            if motion.robot is not None:
                args[motion.robot] = robot
            specs[name] = tuple(args)
            motions[name] = MotionAction(motion.robot, motion.destination)
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


def robot_name(config: Mapping[str, Any], key: str) -> str:
    """The entry's ``robot`` (checked again by :class:`CanSettings`), lower case."""
    robot = config.get("robot")
    if not isinstance(robot, str) or not robot.strip():
        raise ConfigError("the PDDL object this base is (a non-empty string)", key=f"{key}.robot")
    return robot.strip().lower()


def resolve(settings: CanSettings, actions: object, base_dir: Path, key: str) -> CanBaseSettings:
    """The performer's settings: files loaded, the bus chosen (python-can's
    configuration chain when the entry names no interface)."""
    robot = settings.robot.strip().lower()
    _specs, motions = parse_motions(actions, robot, f"{key}.actions")
    locations = load_locations(settings.locations, base_dir, f"{key}.locations")
    bus = settings.bus
    replay = settings.replay not in (None, False)
    if replay and settings.simulate_base is not None:
        raise ConfigError("a base is either simulated or replayed, not both", key=f"{key}.replay")
    try:
        interface, channel, origin = choose_interface(
            bus.interface, bus.channel, simulated=replay or settings.simulate_base is not None
        )
    except ValueError as exc:
        raise ConfigError(str(exc), key=f"{key}.bus.interface") from exc
    if replay and interface != "virtual":
        raise ConfigError(
            f"a recorded log is replayed on the 'virtual' interface, not {interface!r}",
            key=f"{key}.replay",
        )
    if settings.simulate_base is not None and interface != "virtual":
        raise ConfigError(
            f"the simulated base runs only on the 'virtual' interface, not {interface!r} "
            "(from python-can's configuration); remove simulate_base to drive a real base",
            key=f"{key}.simulate_base",
        )
    dbc = None if settings.dbc is None else Path(settings.dbc)
    if dbc is not None and not dbc.is_absolute():
        dbc = base_dir / dbc
    if dbc is not None:
        try:
            MobileBaseDbc.load(dbc)  # a missing or broken file is an error of this key
        except PlansysBridgeError as exc:
            raise ConfigError(str(exc), key=f"{key}.dbc") from exc
    return CanBaseSettings(
        robot=robot,
        motions=motions,
        locations=locations,
        bus=BusConfig(
            interface=interface,
            channel=channel,
            bitrate=bus.bitrate,
            reader=bus.reader,
            poll_period=bus.poll_period,
            send_timeout=bus.send_timeout,
            reopen_period=bus.reopen_period,
            options=dict(bus.options),
            origin=origin,
        ),
        dbc=dbc,
        controller=_split(settings.controller, ControllerConfig, MotionLimits, f"{key}.controller"),
        safety=settings.safety,
        battery=settings.battery,
        simulate_base=(
            None
            if settings.simulate_base is None
            else _split(
                settings.simulate_base, BaseDoubleConfig, BaseLimits, f"{key}.simulate_base"
            )
        ),
        feedback_period=settings.feedback_period,
        record_topic=settings.record_topic or f"/{robot}/pose",
        record_period=settings.record_period,
        replay=parse_replay(settings.replay, base_dir, f"{key}.replay"),
    )


__all__ = [
    "BatterySettings",
    "BusSettings",
    "CanBaseSettings",
    "CanSettings",
    "Location",
    "MotionAction",
    "SafetySettings",
    "load_locations",
    "parse_motions",
    "resolve",
    "robot_name",
]
