"""The sensing-source plugin shape: its base class and its entry-point registry.

A sensing source kind is a :class:`~plansys_bridge.sensing.sources.SensingSource`
subclass registered by name in the ``plansys_bridge.sensing_sources`` entry-point
group, with the keys a rule gives it declared as a pydantic ``Settings`` model: the
same shape as performers, solvers and transports (:mod:`plansys_bridge.plugins`).
"""

from __future__ import annotations

from plansys_bridge.plugins import GROUPS, PluginRegistry
from plansys_bridge.sensing.sources import BUILTIN, SensingSource

__all__ = ["SENSING_SOURCES", "SensingSource"]

SENSING_SOURCES: PluginRegistry[SensingSource] = PluginRegistry(
    GROUPS["sensing_sources"], SensingSource, "sensing source", builtin=BUILTIN
)
"""The sensing source kinds installed (entry-point group ``plansys_bridge.sensing_sources``)."""
