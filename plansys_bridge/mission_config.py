"""Mission files: the YAML a user writes to run a mission with ``plansys-bridge run``.

The file is validated completely on load, before any performer starts or any
hardware is touched: a typo in a key is an error naming the place and the key
(``mission.yaml:9:5: performers[1].acions: unknown key``), never a silently ignored
setting. The sections that belong to a plugin (each performer entry, the
transport) are validated through the plugin's own ``Settings`` model
(:mod:`plansys_bridge.plugins`); what needs files or the knowledge is checked when
the performers are built, still before any of them connects.
Relative paths are resolved against the folder of the YAML file.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    field_validator,
    model_validator,
)

from plansys_bridge.errors import ConfigError, PluginError
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.planning.planner import Planner
from plansys_bridge.plugins import key_path, validate_settings, validation_message
from plansys_bridge.yaml_files import (
    MAX_YAML_DEPTH,
    KeyPositions,
    load_yaml_document,
    load_yaml_file,
)

if TYPE_CHECKING:
    from plansys_bridge.hub.transport_kinds import TransportKind

__all__ = [
    "MAX_YAML_DEPTH",
    "MissionConfig",
    "load_mission",
    "load_yaml_file",
    "make_planner",
    "mission_from_dict",
]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ClockConfig(_Strict):
    """``wall`` runs in real time; ``virtual`` jumps over idle time (tests, experiments)."""

    kind: Literal["wall", "virtual"] = "wall"
    time_scale: float = Field(1.0, gt=0)
    """Every action duration is multiplied by this (0.05 runs 20x faster)."""

    @model_validator(mode="after")
    def _scale_needs_wall(self) -> ClockConfig:
        if self.kind == "virtual" and self.time_scale != 1.0:
            raise ValueError(
                "time_scale applies to the wall clock; the virtual clock skips idle time"
            )
        return self


class TransportConfig(BaseModel):
    """Which transport carries the hub's messages, by the name of its plugin
    (:mod:`plansys_bridge.hub.transport_kinds`): ``inprocess`` (one process, the
    default), ``dds`` (Cyclone DDS, so the performers may run in other processes,
    ``plansys-bridge performers MISSION.yaml``, and on other hosts) or one a package
    registers. The other keys are the kind's settings, validated by its ``Settings``."""

    model_config = ConfigDict(extra="allow", frozen=True)
    kind: str = "inprocess"

    def settings(self) -> dict[str, Any]:
        """The keys besides ``kind``, for the kind's ``Settings`` model."""
        return dict(self.model_extra or {})


class PlannerConfig(_Strict):
    """Which solver plans the mission, by name, and its options.

    ``solver`` is a name from ``plansys-bridge plan --list-solvers`` (or a list, tried
    in order); without one the planner picks the first installed solver that supports
    the task. ``options`` maps a solver name to its options
    (``{kairos: {improve_for: 5}}``) or gives an option to every listed solver that
    takes it (``{threads: 1}``).
    """

    solver: str | list[str] | None = None
    timeout: float = Field(30.0, gt=0)
    """Seconds each planning (and replanning) may take."""
    options: dict[str, Any] = Field(default_factory=dict)
    fallback: bool = False
    """A solver that errs or times out hands over to the next listed one."""


class AuthConfig(_Strict):
    """A fleet key: the hub accepts auction messages and heartbeats only when signed
    with it (:mod:`plansys_bridge.hub.auth`)."""

    key_file: str
    window: float = Field(30.0, gt=0)
    """Seconds a signed message's timestamp may differ from the receiver's clock."""


class KnowledgeConfig(_Strict):
    """Initial knowledge given inline instead of (or on top of) a problem file."""

    instances: dict[str, str] = Field(default_factory=dict)
    predicates: list[str] = Field(default_factory=list)
    functions: list[str] = Field(default_factory=list)
    function_files: list[str] = Field(default_factory=list)
    """Files of ``(= (f a) 1.5)`` entries (``learn --functions`` writes them), set
    after ``functions``, so learned values replace the guesses."""


class EventConfig(_Strict):
    """A change to the knowledge at a mission time, e.g. a battery drop."""

    at: float = Field(ge=0)
    add_predicate: str | None = None
    remove_predicate: str | None = None
    set_function: str | None = None

    @model_validator(mode="after")
    def _exactly_one(self) -> EventConfig:
        given = [
            k for k in ("add_predicate", "remove_predicate", "set_function") if getattr(self, k)
        ]
        if len(given) != 1:
            raise ValueError(
                "an event needs exactly one of add_predicate, remove_predicate, set_function"
            )
        return self


class PerformerEntry(BaseModel):
    """Common keys of a performer; the plugin validates the rest."""

    model_config = ConfigDict(extra="allow", frozen=True)
    kind: str
    name: str


class MissionConfig(_Strict):
    name: str = "mission"
    domain: list[str] = Field(min_length=1)
    problem: str | None = None
    knowledge: KnowledgeConfig = Field(default_factory=KnowledgeConfig)
    goal: str | None = None
    performers: list[PerformerEntry] = Field(min_length=1)
    transport: TransportConfig = Field(default_factory=TransportConfig)
    auth: AuthConfig | None = None
    """A fleet key: only signed auction messages and heartbeats are accepted."""
    planner: PlannerConfig = Field(default_factory=PlannerConfig)
    clock: ClockConfig = Field(default_factory=ClockConfig)
    replanning: dict[str, Any] = Field(default_factory=dict)
    """``max_replans``; checked by :class:`ExecutorOptions`."""
    auction: dict[str, Any] = Field(default_factory=dict)
    """:class:`~plansys_bridge.hub.auction.AuctionPolicy` settings."""
    execution: dict[str, Any] = Field(default_factory=dict)
    """:class:`~plansys_bridge.execution.options.ExecutorOptions` settings
    (``at_start_timeout``, ``overrun_percentage``, ...)."""
    events: list[EventConfig] = Field(default_factory=list)
    sensing: list[Any] = Field(default_factory=list)
    """Rules writing sensor values into the knowledge; checked by
    :mod:`plansys_bridge.sensing.load` against the domain and the performers."""
    record: str | None = None
    """Write the whole run to this ROS 2 bag (mcap)."""
    bid_costs: str | None = None
    """Learned per-performer costs (``learn --costs``), bid instead of the performers' own."""
    timeout: float | None = Field(None, gt=0)
    """Give up the mission after this many seconds of mission time."""
    bridge: dict[str, Any] | None = None
    """ROS 1 <-> ROS 2 topics to bridge while the mission runs (a bridge file's keys:
    ``ros1``, ``ros2``, ``topics``); checked by :mod:`plansys_bridge.bridge.config`."""

    base_dir: Path = Path(".")
    source: str = "<mission>"

    @field_validator("domain", mode="before")
    @classmethod
    def _domain_list(cls, value: Any) -> Any:
        if isinstance(value, str):
            return [value]
        if not isinstance(value, list):  # YAML's .nan, 3, true: "valid list" would mislead
            raise ValueError(f"a domain file path or a list of them, got {value!r}")
        return value

    @model_validator(mode="after")
    def _has_goal(self) -> MissionConfig:
        if self.problem is None and self.goal is None:
            raise ValueError("a mission needs a problem file or a goal")
        names = [p.name for p in self.performers]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"performer names must be unique, repeated: {', '.join(dupes)}")
        return self

    _positions: KeyPositions | None = PrivateAttr(default=None)
    _transport: TransportKind | None = PrivateAttr(default=None)

    def error(self, message: str, key: str | None = None) -> ConfigError:
        """A ConfigError about ``key`` of this mission file, with its line and column."""
        return self.locate(ConfigError(message, key=key))

    def locate(self, exc: ConfigError) -> ConfigError:
        """``exc`` naming this file and, when known, the line and column of its key
        (unchanged when it is about another file)."""
        positions = self._positions or KeyPositions(self.source)
        if exc.file is None:
            exc = ConfigError(exc.reason, key=exc.key, file=self.source)
        return positions.relocate(exc)

    def transport_kind(self) -> TransportKind:
        """The ``transport:`` plugin with its settings validated."""
        if self._transport is None:
            self._transport = _transport_kind(self)
        return self._transport

    def resolve(self, path: str) -> Path:
        """A path from the file, relative to the file's folder."""
        p = Path(path).expanduser()
        return p if p.is_absolute() else (self.base_dir / p).resolve()

    @property
    def domain_paths(self) -> list[Path]:
        return [self.resolve(d) for d in self.domain]

    def executor_options(self) -> ExecutorOptions:
        """The executor settings of the ``execution``, ``auction`` and ``replanning`` keys."""
        defaults = {"max_replans": 3}
        try:
            return ExecutorOptions.from_config(
                self.execution, auction=self.auction, replanning=defaults | self.replanning
            )
        except ConfigError as exc:
            raise ConfigError(str(exc).split(": ", 1)[-1], key=exc.key, file=self.source) from exc


def make_planner(mission: MissionConfig) -> Planner:
    """The planner the ``planner:`` section asks for; errors name its keys."""
    config = mission.planner
    solvers = [config.solver] if isinstance(config.solver, str) else config.solver
    try:
        return Planner(
            solvers=solvers,
            timeout=config.timeout,
            options=config.options,
            fallback=config.fallback,
        )
    except PluginError as exc:
        raise ConfigError(str(exc), key="planner.solver", file=mission.source) from exc
    except ConfigError as exc:
        key = exc.key or ""
        key = f"options.{key.removeprefix('solvers.')}" if key.startswith("solvers") else key
        message = str(exc).removeprefix(f"{exc.key}: ") if exc.key else str(exc)
        raise ConfigError(message, key=f"planner.{key}".rstrip("."), file=mission.source) from exc


def _find_nul(value: Any, where: tuple[int | str, ...]) -> tuple[tuple[int | str, ...], str] | None:
    """The first string (key or value) holding a NUL byte, and where it is.

    File systems refuse such names with a bare ValueError wherever the path is
    used (domain, locations, bags, DBC files), so the whole file is checked once."""
    stack: list[tuple[Any, tuple[int | str, ...]]] = [(value, where)]
    while stack:
        item, at = stack.pop()
        if isinstance(item, str):
            if "\0" in item:
                return at, item
        elif isinstance(item, dict):
            for k, v in item.items():
                if isinstance(k, str) and "\0" in k:
                    return at, k
                stack.append((v, (*at, str(k))))
        elif isinstance(item, list):
            stack.extend((v, (*at, i)) for i, v in enumerate(item))
    return None


def mission_from_dict(
    data: Any,
    *,
    source: str = "<mission>",
    base_dir: Path | None = None,
    positions: KeyPositions | None = None,
) -> MissionConfig:
    """Validate a mission mapping, every plugin's section through the plugin's own
    ``Settings``; errors name the first offending key (with its line and column
    when ``positions`` says where the keys are)."""
    where = positions or KeyPositions(source)
    try:
        mission = _validate(data, source, base_dir or Path("."))
        mission._positions = where
        _check_plugins(mission)
    except ConfigError as exc:
        raise where.relocate(exc) from exc
    return mission


def _validate(data: Any, source: str, base_dir: Path) -> MissionConfig:
    if not isinstance(data, dict):
        raise ConfigError("a mission file must be a mapping of keys", file=source)
    for reserved in ("base_dir", "source"):
        if reserved in data:
            raise ConfigError("unknown key", key=reserved, file=source)
    nul = _find_nul(data, ())
    if nul is not None:
        at, text = nul
        raise ConfigError(
            f"a NUL byte in {text!r} (no file name or setting holds one)",
            key=key_path(at) or None,
            file=source,
        )
    try:
        mission = MissionConfig.model_validate({**data, "base_dir": base_dir, "source": source})
    except ValidationError as exc:
        err = exc.errors()[0]
        raise ConfigError(
            validation_message(err), key=key_path(err["loc"]) or None, file=source
        ) from exc
    mission.executor_options()  # the executor's own checks, errors naming the key
    if mission.planner != PlannerConfig():
        make_planner(mission)  # unknown solvers and options are errors now, not at planning
    if mission.bid_costs is not None:
        from plansys_bridge.performers.bid_costs import load_bid_costs

        load_bid_costs(mission.resolve(mission.bid_costs))
    if mission.bridge is not None:
        from plansys_bridge.bridge.config import parse_bridge_config

        parse_bridge_config(mission.bridge, source=source or "", key="bridge")
    return mission


def _check_plugins(mission: MissionConfig) -> None:
    """The transport's and each performer's settings, through the plugin's model.

    A performer kind that is not registered is an error here; one whose optional
    dependency is missing on this host is reported when its performers are built
    (the executor of a distributed mission need not have every adapter installed).
    """
    from plansys_bridge.performers.registry import PERFORMERS

    kind = mission.transport_kind()
    if kind.wall_clock_only and mission.clock.kind == "virtual":
        raise mission.error(
            f"the {mission.transport.kind} transport needs the wall clock (the virtual "
            "clock would expire protocol timeouts while messages travel between processes)",
            key="clock.kind",
        )
    for i, entry in enumerate(mission.performers):
        where = f"performers[{i}]"
        if PERFORMERS.reference(entry.kind) is None:
            known = ", ".join(PERFORMERS.names())
            raise mission.error(
                f"unknown performer kind {entry.kind!r} (known: {known})", key=f"{where}.kind"
            )
        try:
            cls = PERFORMERS.load(entry.kind)
        except PluginError:
            continue
        cls.parse_config(entry.model_dump(), key=where)


def _transport_kind(mission: MissionConfig) -> TransportKind:
    from plansys_bridge.hub.transport_kinds import TRANSPORTS

    name = mission.transport.kind
    try:
        cls = TRANSPORTS.load(name)
    except PluginError as exc:
        raise mission.error(str(exc), key="transport.kind") from exc
    settings = mission.transport.settings()
    try:
        return cls(validate_settings(cls.Settings, settings, key="transport"))
    except ConfigError as exc:
        unknown = (exc.key or "").removeprefix("transport.")
        if "unknown key" in exc.reason and unknown in settings:
            others = _kinds_with_setting(unknown)
            if others:
                raise mission.error(
                    f"{unknown} applies to the {' and '.join(others)} transport only",
                    key=exc.key,
                ) from exc
        raise mission.locate(exc) from exc


def _kinds_with_setting(name: str) -> list[str]:
    """The installed transport kinds that take a setting called ``name``."""
    from plansys_bridge.hub.transport_kinds import TRANSPORTS

    found = []
    for kind in TRANSPORTS.names():
        try:
            if name in TRANSPORTS.load(kind).Settings.model_fields:
                found.append(kind)
        except PluginError:
            continue
    return found


def load_mission(path: str | Path) -> MissionConfig:
    """Read and validate a mission YAML file."""
    p = Path(path)
    data, positions = load_yaml_document(p, "mission file")
    return mission_from_dict(data, source=str(p), base_dir=p.resolve().parent, positions=positions)
