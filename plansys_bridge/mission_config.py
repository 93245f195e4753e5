"""Mission files: the YAML a user writes to run a mission with ``plansys-bridge run``.

The file is validated completely on load, before any performer starts or any
hardware is touched: a typo in a key is an error naming that key
(``mission.yaml: performers[1].acions: unknown key``), never a silently ignored
setting. Performer entries are checked twice: the common keys here, the
kind-specific settings by the performer plugin's own ``from_config``.
Relative paths are resolved against the folder of the YAML file.
"""

from __future__ import annotations

import contextlib
import ipaddress
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from plansys_bridge.errors import ConfigError, PluginError
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.planning.planner import Planner
from plansys_bridge.textfile import TextFileError, read_text


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


class TransportConfig(_Strict):
    """``inprocess``: one process; ``dds``: Cyclone DDS, so the performers may run in
    other processes (``plansys-bridge performers MISSION.yaml``) and on other hosts.

    DDS stays on 127.0.0.1 unless told otherwise: ``interfaces`` (addresses or names)
    and ``peers`` (hosts to discover by unicast) and ``multicast`` describe a real
    network; ``config`` names a Cyclone XML file instead (what ``CYCLONEDDS_URI`` would
    hold), for anything beyond that.
    """

    kind: Literal["inprocess", "dds"] = "inprocess"
    domain_id: int = Field(0, ge=0, le=232)
    """DDS domain; processes of one mission share it, other runs pick another."""
    peer_timeout: float = Field(10.0, gt=0)
    """With remote performers: seconds to wait for a heartbeat from each of them."""
    interfaces: list[str] = Field(default_factory=lambda: ["127.0.0.1"], min_length=1)
    """Network interfaces DDS uses, by address or name (default: loopback only)."""
    peers: list[str] | None = None
    """Hosts (address or name, optionally ``:port``) found by unicast discovery; by
    default the interfaces' own addresses, so processes of this machine meet."""
    multicast: bool = False
    """Discover and send by multicast on the interfaces (off: unicast to ``peers``)."""
    config: str | None = None
    """A Cyclone DDS XML file (relative to the mission file) used instead of the above."""

    @model_validator(mode="after")
    def _dds_settings_need_dds(self) -> TransportConfig:
        dds_only = {"domain_id", "peer_timeout", "interfaces", "peers", "multicast", "config"}
        extra = sorted(self.model_fields_set & dds_only)
        if self.kind != "dds" and extra:
            raise ValueError(f"{', '.join(extra)} applies to the dds transport only")
        network = sorted(self.model_fields_set & {"interfaces", "peers", "multicast"})
        if self.config is not None and network:
            raise ValueError(
                f"config (a Cyclone XML file) replaces {', '.join(network)}: give one or the other"
            )
        return self

    def peer_list(self) -> list[str]:
        """``peers``, or the interfaces that are addresses when ``peers`` is not given."""
        if self.peers is not None:
            return list(self.peers)
        found = []
        for value in self.interfaces:
            with contextlib.suppress(ValueError):
                found.append(str(ipaddress.ip_address(value)))
        return found


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
        return [value] if isinstance(value, str) else value

    @model_validator(mode="after")
    def _dds_needs_wall_clock(self) -> MissionConfig:
        if self.transport.kind == "dds" and self.clock.kind == "virtual":
            raise ValueError(
                "the dds transport needs the wall clock (the virtual clock would expire "
                "protocol timeouts while messages travel between processes)"
            )
        return self

    @model_validator(mode="after")
    def _has_goal(self) -> MissionConfig:
        if self.problem is None and self.goal is None:
            raise ValueError("a mission needs a problem file or a goal")
        names = [p.name for p in self.performers]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"performer names must be unique, repeated: {', '.join(dupes)}")
        return self

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


def _key_path(loc: tuple[int | str, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


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
    data: Any, *, source: str = "<mission>", base_dir: Path | None = None
) -> MissionConfig:
    """Validate a mission mapping; errors name the first offending key."""
    if not isinstance(data, dict):
        raise ConfigError("a mission file must be a mapping of keys", file=source)
    for reserved in ("base_dir", "source"):
        if reserved in data:
            raise ConfigError("unknown key", key=reserved, file=source)
    nul = _find_nul(data, ())
    if nul is not None:
        where, text = nul
        raise ConfigError(
            f"a NUL byte in {text!r} (no file name or setting holds one)",
            key=_key_path(where) or None,
            file=source,
        )
    try:
        mission = MissionConfig.model_validate(
            {**data, "base_dir": base_dir or Path("."), "source": source}
        )
    except ValidationError as exc:
        err = exc.errors()[0]
        msg = "unknown key" if err["type"] == "extra_forbidden" else err["msg"]
        msg = msg.removeprefix("Value error, ")
        raise ConfigError(msg, key=_key_path(err["loc"]) or None, file=source) from exc
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


class _UniqueKeyLoader(yaml.SafeLoader):
    """YAML keeps the last of two equal keys; in a mission file the first is then a
    setting silently ignored (two ``performers:`` lists, two ``goal:``), so it is an error."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[Any] = set()
        for key_node, _value in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue  # ``<<: *anchor``: its keys may be overridden
            key = self.construct_object(key_node, deep=deep)
            if not isinstance(key, str | int | float | bool):
                continue  # an unhashable key: the base class reports it
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark
                )
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


MAX_YAML_DEPTH = 100
"""Deeper nesting is refused before PyYAML builds it (its recursive composer would
end in a RecursionError; no settings file needs more than a handful of levels)."""


def _check_depth(text: str, path: Path, key: str | None) -> None:
    """Walk the YAML events (PyYAML's parser is not recursive) and refuse nesting
    deeper than MAX_YAML_DEPTH, naming the place and the key path that leads there."""
    # each open container: [is_mapping, next_is_key, current key/index]
    stack: list[list[Any]] = []
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.CollectionEndEvent):
            stack.pop()
            _advance(stack)
            continue
        if not isinstance(event, yaml.NodeEvent):
            continue
        top = stack[-1] if stack else None
        if top is not None and top[0] and top[1]:  # a mapping key
            value = getattr(event, "value", None)
            top[2] = value if isinstance(value, str) else "?"
            top[1] = False
            if isinstance(event, yaml.CollectionStartEvent):
                stack.append([isinstance(event, yaml.MappingStartEvent), True, 0])
            continue
        if isinstance(event, yaml.CollectionStartEvent):
            if len(stack) >= MAX_YAML_DEPTH:
                mark = event.start_mark
                where = _key_path(tuple(level[2] for level in stack[:4])) + "..."
                raise ConfigError(
                    f"nested more than {MAX_YAML_DEPTH} levels deep",
                    key=f"{key}: {where}" if key else where,
                    file=f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path),
                )
            stack.append([isinstance(event, yaml.MappingStartEvent), True, 0])
            continue
        _advance(stack)


def _advance(stack: list[list[Any]]) -> None:
    """A value was completed in the innermost container: expect the next key or item."""
    if not stack:
        return
    top = stack[-1]
    if top[0]:
        top[1] = True
    else:
        top[2] += 1


def load_yaml_file(path: str | Path, what: str = "file", key: str | None = None) -> Any:
    """Read a YAML file a user names (mission, locations, segments, ...).

    Unreadable or binary files, YAML syntax errors and repeated keys become one
    ConfigError naming the file (with line:col where YAML knows it) and ``key``,
    the mission key that named the file.
    """
    p = Path(path)
    try:
        text = read_text(p, what)
    except TextFileError as exc:
        raise ConfigError(exc.reason, key=key, file=str(exc.location or p)) from exc
    try:
        _check_depth(text, p, key)
        return yaml.load(text, Loader=_UniqueKeyLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{p}:{mark.line + 1}:{mark.column + 1}" if mark is not None else str(p)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"not valid YAML: {problem}", key=key, file=where) from exc


def load_mission(path: str | Path) -> MissionConfig:
    """Read and validate a mission YAML file."""
    p = Path(path)
    data = load_yaml_file(p, "mission file")
    return mission_from_dict(data, source=str(p), base_dir=p.resolve().parent)
