"""Which recorded stretch of which bag serves which move, and progress along it.

A :class:`Segment` says: an action whose arguments match ``arguments`` (position by
position, ``""`` or ``"*"`` matches anything, as PlanSys2's specialized arguments) is
replayed from ``bag``/``topic`` between ``start`` and ``end`` seconds after the bag's
first message. A :class:`Route` holds the segments of one performer and picks the
first one that matches.

Completion is the fraction of the recorded path already travelled, by arc length,
so a robot that waits at a door and then drives reports the progress it actually
made. The path length is measured once per segment in a streaming pass
(:func:`profile_segment`) so nothing is kept in memory but a few numbers.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import Field, ValidationInfo, field_validator, model_validator

from plansys_bridge.errors import ConfigError
from plansys_bridge.plugins import PluginSettings, validate_settings
from plansys_bridge.yaml_files import KeyPositions, load_yaml_document

from .errors import BagError
from .reader import BagReader, PoseSample

WILDCARDS = frozenset({"", "*"})


@dataclass(frozen=True)
class Segment:
    """A time window of one pose topic in one bag, serving matching actions."""

    bag: Path
    topic: str
    arguments: tuple[str, ...] = ()
    action: str | None = None
    start: float | None = None
    """Seconds after the bag's first message (``None``: from the beginning)."""
    end: float | None = None
    """Seconds after the bag's first message (``None``: to the end)."""
    name: str = ""

    def matches(self, action: str, arguments: Sequence[str]) -> bool:
        if self.action is not None and self.action != action:
            return False
        if len(self.arguments) != len(arguments):
            return False
        return all(
            want in WILDCARDS or want == got
            for want, got in zip(self.arguments, arguments, strict=True)
        )

    def describe(self) -> str:
        window = f"[{self.start if self.start is not None else 'start'}, "
        window += f"{self.end if self.end is not None else 'end'}] s"
        label = self.name or " ".join(self.arguments) or "any"
        return f"segment {label!r} ({self.bag} {self.topic} {window})"

    def window_ns(self, bag: BagReader) -> tuple[int | None, int | None]:
        """The absolute ``[start, stop)`` bag times of this window in ``bag``."""
        start = bag.start_ns + round(self.start * 1e9) if self.start is not None else None
        # rosbags' stop is exclusive; +1 ns makes ``end`` itself part of the window.
        stop = bag.start_ns + round(self.end * 1e9) + 1 if self.end is not None else None
        return start, stop

    def poses(self, bag: BagReader) -> Iterator[PoseSample]:
        start, stop = self.window_ns(bag)
        return bag.poses(self.topic, start, stop)


class SegmentSpec(PluginSettings):
    """One item of a ``segments`` list as written. A model, so that an inline list is
    checked with the rest of the entry when the mission loads (a segments file is
    checked the same way when the performer is built)."""

    arguments: list[str] = Field(default_factory=list)
    """The action's arguments, position by position (``""``/``"*"`` match anything)."""
    action: str | None = Field(None, min_length=1)
    """Only this action (None: any action with matching arguments)."""
    bag: str = Field(None, min_length=1, validate_default=True)
    """The bag, relative to the mission file (default: the performer's ``bag``)."""
    topic: str = Field(None, min_length=1, validate_default=True)
    """The pose topic (default: the performer's ``topic``)."""
    start: float | None = Field(None, ge=0.0)
    """Seconds after the bag's first message (None: from the beginning)."""
    end: float | None = Field(None, ge=0.0)
    """Seconds after the bag's first message (None: to the end)."""
    name: str = ""

    @model_validator(mode="before")
    @classmethod
    def _mapping(cls, value: object) -> object:
        """Say what an item must be (pydantic would name this class)."""
        if isinstance(value, Mapping | SegmentSpec):
            return value
        raise ValueError(
            f"a segment must be a mapping of {', '.join(cls.model_fields)}, got {value!r}"
        )

    @field_validator("bag", "topic", mode="before")
    @classmethod
    def _given(cls, value: object, info: ValidationInfo) -> object:
        """Neither the segment nor the performer names it (see :func:`with_defaults`)."""
        if value is None:
            raise ValueError(
                f"missing: give the segment's {info.field_name} or the performer's "
                f"default {info.field_name}"
            )
        return value

    @field_validator("end")
    @classmethod
    def _after_start(cls, value: float | None, info: ValidationInfo) -> float | None:
        start = info.data.get("start")
        if value is not None and start is not None and value <= start:
            raise ValueError(f"end ({value}) must be after start ({start})")
        return value


def distance(a: PoseSample, b: PoseSample) -> float:
    return math.sqrt((b.x - a.x) ** 2 + (b.y - a.y) ** 2 + (b.z - a.z) ** 2)


@dataclass(frozen=True)
class SegmentProfile:
    """What one streaming pass over a segment learns: size, duration, path length."""

    count: int
    first_ns: int
    last_ns: int
    length: float
    """Path length in metres (3-D arc length of the recorded positions)."""
    start: tuple[float, float, float]
    end: tuple[float, float, float]

    @property
    def duration(self) -> float:
        """Recorded duration in seconds, first to last pose."""
        return (self.last_ns - self.first_ns) / 1e9


def profile_segment(segment: Segment) -> SegmentProfile:
    """Measure a segment in one streaming pass; BagError if it holds no pose."""
    with BagReader(segment.bag) as bag:
        count = 0
        length = 0.0
        first: PoseSample | None = None
        prev: PoseSample | None = None
        for sample in segment.poses(bag):
            if first is None:
                first = sample
            if prev is not None:
                length += distance(prev, sample)
            prev = sample
            count += 1
        if first is None or prev is None:
            raise BagError(
                f"{segment.describe()} holds no message "
                f"(bag spans {(bag.end_ns - bag.start_ns) / 1e9:.3f} s)",
                segment.bag,
                segment.topic,
            )
    return SegmentProfile(
        count=count,
        first_ns=first.bag_time_ns,
        last_ns=prev.bag_time_ns,
        length=length,
        start=(first.x, first.y, first.z),
        end=(prev.x, prev.y, prev.z),
    )


@dataclass
class PathProgress:
    """Completion along a recorded path, fed one pose at a time.

    Falls back to elapsed time when the path is (nearly) zero length, e.g. a robot
    that only turns on the spot, so completion still goes from 0 to 1.
    """

    profile: SegmentProfile
    travelled: float = 0.0
    _prev: PoseSample | None = field(default=None, repr=False)

    MIN_LENGTH = 1e-3

    def update(self, sample: PoseSample) -> float:
        if self._prev is not None:
            self.travelled += distance(self._prev, sample)
        self._prev = sample
        return self.completion(sample)

    def completion(self, sample: PoseSample) -> float:
        if self.profile.length >= self.MIN_LENGTH:
            value = self.travelled / self.profile.length
        elif self.profile.last_ns > self.profile.first_ns:
            value = (sample.bag_time_ns - self.profile.first_ns) / (
                self.profile.last_ns - self.profile.first_ns
            )
        else:
            value = 1.0
        return min(1.0, max(0.0, value))


class RouteError(ConfigError):
    """No segment of the route serves an action."""


@dataclass
class Route:
    """The segments of one performer, tried in order."""

    segments: list[Segment]
    _profiles: dict[Segment, SegmentProfile] = field(default_factory=dict, repr=False)

    def select(self, action: str, arguments: Sequence[str]) -> Segment:
        for segment in self.segments:
            if segment.matches(action, arguments):
                return segment
        text = f"({' '.join((action, *arguments))})"
        raise RouteError(f"no bag segment serves {text}", key="segments")

    def profile(self, segment: Segment) -> SegmentProfile:
        """The segment's profile, measured on first use and kept."""
        if segment not in self._profiles:
            self._profiles[segment] = profile_segment(segment)
        return self._profiles[segment]

    @classmethod
    def from_config(
        cls,
        entries: Any,
        base_dir: Path,
        *,
        key: str = "segments",
        default_bag: str | None = None,
        default_topic: str | None = None,
    ) -> Route:
        """Build from the ``segments`` of a performer entry: the list, or the path
        (relative to ``base_dir``) of a YAML file holding it, such as the
        ``*.segments.yaml`` the bag generator writes.

        Each item is a :class:`SegmentSpec`; ``default_bag``/``default_topic`` serve the
        items without their own. Wrong keys or values raise ConfigError naming
        ``key[i].field`` (and the file's line and column for a segments file).
        """
        positions: KeyPositions | None = None
        file: str | None = None
        if isinstance(entries, str):
            entries, positions = _load_segments_file(base_dir / entries, key)
            file = positions.file
        if not isinstance(entries, list) or not entries:
            raise ConfigError("expected a non-empty list of segments", key=key, file=file)
        filled = with_defaults(entries, default_bag, default_topic)
        try:
            checked = validate_settings(_SegmentList, {"segments": filled})
        except ConfigError as exc:
            raise _in_segments(exc, key, positions) from exc
        return cls.from_specs(checked.segments, base_dir)

    @classmethod
    def from_specs(cls, specs: Sequence[SegmentSpec], base_dir: Path) -> Route:
        """Build from validated segments; bag paths are relative to ``base_dir``."""
        segments: list[Segment] = []
        for spec in specs:
            path = Path(spec.bag)
            if not path.is_absolute():
                path = (base_dir / path).resolve()
            segments.append(
                Segment(
                    bag=path,
                    topic=spec.topic,
                    arguments=tuple(a.lower() for a in spec.arguments),
                    action=spec.action.lower() if spec.action else None,
                    start=spec.start,
                    end=spec.end,
                    name=spec.name,
                )
            )
        return cls(segments)


def with_defaults(
    entries: Sequence[Any], default_bag: str | None, default_topic: str | None
) -> list[Any]:
    """The segment entries with the performer's ``bag``/``topic`` filled in where an
    entry gives none (copies: the mission file's own data stays as written)."""
    defaults = {"bag": default_bag, "topic": default_topic}
    out: list[Any] = []
    for entry in entries:
        if isinstance(entry, Mapping):
            entry = dict(entry)
            for name, default in defaults.items():
                if entry.get(name) is None and default is not None:
                    entry[name] = default
        out.append(entry)
    return out


class _SegmentList(PluginSettings):
    segments: list[SegmentSpec]


def _in_segments(exc: ConfigError, key: str, positions: KeyPositions | None) -> ConfigError:
    """``exc`` (keyed ``segments[i].field``) keyed below ``key``, and placed in the
    segments file (where the item is ``[i]``) when the list came from one."""
    inner = (exc.key or "").removeprefix("segments")
    where = f"{key}{inner}"
    if positions is None:
        return ConfigError(exc.reason, key=where)
    line, column = positions.locate(inner) or (None, None)
    return ConfigError(exc.reason, key=where, file=positions.file, line=line, column=column)


def _load_segments_file(path: Path, key: str) -> tuple[Any, KeyPositions]:
    return load_yaml_document(path, "segments file", key)
