"""Sensing sources: where a rule's samples come from, as plugins.

A source kind (``mavlink``, ``can``, ``ros1``, ``ros2``) is a :class:`SensingSource`
subclass registered under the ``plansys_bridge.sensing_sources`` entry-point group
and imported only when a mission names it. It declares the rule keys it takes as a
pydantic ``Settings`` model, checks at load time that the message, field or signal
a rule names exists (in pymavlink's dialect, the performer's DBC, the topic's
type), and at run time hooks the adapter's own receive path (a vehicle's listener,
a bus client's frames, a ROS subscription) and hands each decoded message to the
engine as a flat ``{field path: value}`` sample.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from pathlib import Path
from typing import Any, ClassVar

from pydantic import BaseModel

from plansys_bridge.errors import PluginError

from .expressions import Expression, Sample

__all__ = [
    "ENTRY_POINT_GROUP",
    "RuleSite",
    "SensingSource",
    "flatten",
    "load_source_kind",
]

ENTRY_POINT_GROUP = "plansys_bridge.sensing_sources"

Feed = Callable[[Sample], None]
Detach = Callable[[], None]


@dataclass(frozen=True)
class RuleSite:
    """What a source may look at when it checks a rule at load time."""

    performer: Mapping[str, Any] | None
    """The mission's entry of the rule's performer (kind and settings), if it names one."""
    base_dir: Path
    """The mission file's folder (relative paths in performer settings)."""
    mission: Any = None
    """The whole mission configuration (a ROS source reads its ``bridge:``)."""


class SensingSource:
    """One kind of sensor stream (see the module docs).

    Subclasses set ``Settings`` (their rule keys), implement :meth:`check` (load
    time: the names exist; returns the field paths a sample will carry) and
    :meth:`attach` (run time: start feeding samples; returns a function that stops).
    """

    Settings: ClassVar[type[BaseModel]]
    performer_kinds: ClassVar[tuple[str, ...]] = ()
    """Performer kinds whose link this source reads (empty: needs no performer)."""

    def __init__(self, settings: BaseModel) -> None:
        self.settings = settings

    def describe(self) -> str:
        """The stream in a few words, for logs (``BATTERY_STATUS``)."""
        return type(self).__name__

    def check(self, site: RuleSite) -> frozenset[str] | None:
        """Check the names the settings give; the field paths of a sample, or None
        when they cannot be known before the first message (any field is accepted)."""
        raise NotImplementedError

    def value(self) -> Expression | None:
        """The default value of a function rule (the signal, the field), if any."""
        return None

    def attach(self, performer: Any, feed: Feed) -> Detach:
        """Start calling ``feed(sample)`` for every message (on the event loop)."""
        raise NotImplementedError


BUILTIN = {
    "mavlink": "plansys_bridge_adapters.mavlink.sensing:MavlinkMessageSource",
    "can": "plansys_bridge_adapters.can.sensing:CanSignalSource",
    "ros1": "plansys_bridge.sensing.ros:Ros1TopicSource",
    "ros2": "plansys_bridge.sensing.ros:Ros2TopicSource",
}
"""The project's own sources, as its entry points name them: used only for a name the
installed metadata lacks (an editable install made before the source was added)."""


@functools.cache
def load_source_kind(kind: str) -> type[SensingSource]:
    """The source class registered as ``kind``; PluginError when unknown."""
    eps = {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
    ep = eps.get(kind)
    if ep is None and kind in BUILTIN:
        ep = EntryPoint(kind, BUILTIN[kind], ENTRY_POINT_GROUP)
    if ep is None:
        known = ", ".join(sorted({*eps, *BUILTIN})) or "none installed"
        raise PluginError(f"unknown sensing source {kind!r} (known: {known})")
    try:
        cls = ep.load()
    except ImportError as exc:
        raise PluginError(
            f"sensing source {kind!r} needs {exc.name or 'a missing module'}: "
            "install plansys-bridge with the extra of that adapter"
        ) from exc
    if not (isinstance(cls, type) and issubclass(cls, SensingSource)):
        raise PluginError(f"sensing source {kind!r} ({ep.value}) is not a SensingSource")
    return cls


def flatten(value: Any, prefix: str = "", out: dict[str, Any] | None = None) -> dict[str, Any]:
    """A nested message as ``{path: leaf}``: ``pose.position.x``, ``voltages[0]``.

    Mappings and objects with ``__dict__``/``__slots__`` fields nest with dots,
    sequences (not text) with ``[i]``; the sequence itself stays under its own path
    too, so a rule can compare a whole array for equality.
    """
    out = {} if out is None else out
    children: list[tuple[str, Any]] = []
    if isinstance(value, Mapping):
        children = [(f"{prefix}.{k}" if prefix else str(k), v) for k, v in value.items()]
    elif isinstance(value, list | tuple):
        if prefix:
            out[prefix] = value
        children = [(f"{prefix}[{i}]", v) for i, v in enumerate(value)]
    elif hasattr(value, "__dataclass_fields__") or hasattr(value, "__slots__"):
        names: Any = getattr(value, "__dataclass_fields__", None) or getattr(value, "__slots__", ())
        children = [
            (f"{prefix}.{n}" if prefix else n, getattr(value, n))
            for n in names
            if not n.startswith("_") and hasattr(value, n)
        ]
    elif prefix:
        out[prefix] = value
    for path, child in children:
        flatten(child, path, out)
    return out
