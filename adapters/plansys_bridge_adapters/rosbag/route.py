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
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from plansys_bridge.errors import ConfigError
from plansys_bridge.yaml_files import load_yaml_file

from ..checks import mapping
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
        """Build from the ``segments`` list of a performer entry.

        Each entry: ``arguments`` (list; ``""``/``"*"`` wildcard), optional ``action``,
        ``bag`` (relative to ``base_dir``) and ``topic`` (or performer-level defaults),
        optional ``start``/``end`` seconds after the bag's first message, optional
        ``name``. ``entries`` may also be the path (relative to ``base_dir``) of a YAML
        file holding that list, such as the ``*.segments.yaml`` the bag generator
        writes. Wrong keys or values raise ConfigError naming ``key[i].field``.
        """
        if isinstance(entries, str):
            entries = _load_segments_file(base_dir / entries, key)
        if not isinstance(entries, list) or not entries:
            raise ConfigError("expected a non-empty list of segments", key=key)
        allowed = {"arguments", "action", "bag", "topic", "start", "end", "name"}
        segments: list[Segment] = []
        for i, entry in enumerate(entries):
            where = f"{key}[{i}]"
            entry = mapping(entry, where, allowed, "expected a mapping")
            bag = entry.get("bag", default_bag)
            topic = entry.get("topic", default_topic)
            if not isinstance(bag, str) or not bag:
                raise ConfigError("missing bag path", key=f"{where}.bag")
            if not isinstance(topic, str) or not topic:
                raise ConfigError("missing topic", key=f"{where}.topic")
            args = entry.get("arguments", [])
            if not isinstance(args, list) or not all(isinstance(a, str) for a in args):
                raise ConfigError("expected a list of strings", key=f"{where}.arguments")
            action = entry.get("action")
            if action is not None and not isinstance(action, str):
                raise ConfigError("expected an action name", key=f"{where}.action")
            start = _seconds(entry.get("start"), f"{where}.start")
            end = _seconds(entry.get("end"), f"{where}.end")
            if start is not None and end is not None and end <= start:
                raise ConfigError(f"end ({end}) must be after start ({start})", key=f"{where}.end")
            path = Path(bag)
            if not path.is_absolute():
                path = (base_dir / path).resolve()
            segments.append(
                Segment(
                    bag=path,
                    topic=topic,
                    arguments=tuple(a.lower() for a in args),
                    action=action.lower() if action else None,
                    start=start,
                    end=end,
                    name=str(entry.get("name", "")),
                )
            )
        return cls(segments)


def _load_segments_file(path: Path, key: str) -> Any:
    return load_yaml_file(path, "segments file", key)


def _seconds(value: Any, key: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
        raise ConfigError(f"expected seconds >= 0, got {value!r}", key=key)
    return float(value)
