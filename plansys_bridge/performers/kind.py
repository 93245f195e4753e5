"""What a performer kind declares about its mission-file entry.

The kind's own keys (a pydantic ``Settings`` model, or the older ``settings_keys``),
how an entry is checked, and what is prepared once the mission's context is known.
:class:`~plansys_bridge.performers.base.ActionPerformer` inherits this and builds
the performers (``from_config``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from pydantic import BaseModel

from plansys_bridge.performers.entry import PerformerConfig, parse_entry
from plansys_bridge.plugins import NoSettings

if TYPE_CHECKING:
    from plansys_bridge.performers.goal import PerformerContext

__all__ = ["PerformerKind"]


class PerformerKind:
    """The mission-entry side of a performer class."""

    Settings: ClassVar[type[BaseModel]] = NoSettings
    """The kind's mission-file keys besides the common ones, as a pydantic model
    (:class:`~plansys_bridge.plugins.PluginSettings`); validated when the mission
    loads and passed to ``__init__`` as ``settings=``."""
    settings_keys: ClassVar[frozenset[str]] = frozenset()
    """Older shape, still honoured when ``Settings`` is not declared: extra keys
    passed to ``__init__`` as keywords, checked there."""

    @classmethod
    def parse_config(cls, config: Mapping[str, Any], *, key: str = "performer") -> PerformerConfig:
        """Check a mission file's performer entry: the common keys, then the kind's
        ``Settings`` (or, for a kind written before those, its ``settings_keys``)."""
        return parse_entry(cls, config, key=key)

    @classmethod
    def prepare(cls, entry: PerformerConfig, context: PerformerContext) -> PerformerConfig:
        """Optional: checks and loading that need the context (files next to the
        mission, the knowledge) after the settings were validated; returns the entry
        with what changed (``dataclasses.replace(entry, settings=...)``)."""
        return entry
