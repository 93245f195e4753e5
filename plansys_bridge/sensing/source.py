"""The sensing-source plugin shape: its base class and its entry-point registry.

A source kind (``mavlink``, ``can``, ``ros1``, ``ros2``, or a third party's) is a
:class:`SensingSource` subclass registered by name in the
``plansys_bridge.sensing_sources`` entry-point group and imported only when a
mission names it, through :data:`SENSING_SOURCES`, the same
:class:`~plansys_bridge.plugins.PluginRegistry` that finds performers, solvers and
transports (there is no second loader: the project's own sources are entry points
in its ``pyproject.toml`` like anyone else's). It declares the rule keys it takes
as a pydantic ``Settings`` model (a :class:`~plansys_bridge.plugins.PluginSettings`),
checks at load time that the message, field or signal a rule names exists (in
pymavlink's dialect, the performer's DBC, the topic's type), and at run time hooks
the adapter's own receive path (a vehicle's listener, a bus client's frames, a ROS
subscription) and hands each decoded message to the engine as a flat
``{field path: value}`` sample.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from pydantic import BaseModel

from plansys_bridge.plugins import GROUPS, NoSettings, PluginRegistry

from .expressions import Expression, Sample

__all__ = [
    "SENSING_SOURCES",
    "Detach",
    "Feed",
    "RuleSite",
    "SensingSource",
    "flatten",
]

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

    Subclasses set ``Settings`` (their rule keys besides the common ``from``,
    ``performer``, ``when``... ; default: none), implement :meth:`check` (load time:
    the names exist; returns the field paths a sample will carry) and :meth:`attach`
    (run time: start feeding samples; returns a function that stops).
    """

    Settings: ClassVar[type[BaseModel]] = NoSettings
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


SENSING_SOURCES: PluginRegistry[SensingSource] = PluginRegistry(
    GROUPS["sensing_sources"],
    SensingSource,
    "sensing source",
    builtin={
        "mavlink": "plansys_bridge_adapters.mavlink.sensing:MavlinkMessageSource",
        "can": "plansys_bridge_adapters.can.sensing:CanSignalSource",
        "ros1": "plansys_bridge.sensing.ros:Ros1TopicSource",
        "ros2": "plansys_bridge.sensing.ros:Ros2TopicSource",
    },
)
"""The sensing source kinds installed (entry-point group ``plansys_bridge.sensing_sources``);
``builtin`` is the project's own entries as its pyproject registers them, consulted
only for a name the installed metadata lacks (see PluginRegistry)."""


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
