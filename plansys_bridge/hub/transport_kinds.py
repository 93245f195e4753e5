"""Transport plugins: what a mission's ``transport: {kind: ...}`` builds.

A transport kind is a :class:`TransportKind` subclass registered in the
``plansys_bridge.transports`` entry-point group, with its mission-file settings as
a pydantic ``Settings`` model (:mod:`plansys_bridge.plugins`). It says what the
rest of the system must know about it (can performers in other processes join?
does it need the wall clock?) so nothing else tests a transport's name, and it
builds the :class:`~plansys_bridge.hub.transport.Transport` the hub runs on.

The built-in kinds: ``inprocess`` (one process, the default) and ``dds`` (Cyclone
DDS, so performers may run in other processes and on other hosts).
"""

from __future__ import annotations

import contextlib
import ipaddress
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from pydantic import BaseModel, Field, model_validator

from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.hub.transport import InProcessTransport, Transport
from plansys_bridge.plugins import GROUPS, NoSettings, PluginRegistry, PluginSettings
from plansys_bridge.textfile import read_text

__all__ = [
    "TRANSPORTS",
    "DdsKind",
    "DdsSettings",
    "InProcessKind",
    "TransportContext",
    "TransportKind",
]


@dataclass(frozen=True)
class TransportContext:
    """What a transport is built with besides its settings."""

    base_dir: Path = field(default_factory=Path)
    """Folder of the mission file: relative paths in the settings start here."""
    node_name: str = "plansys_bridge"
    """The name this process shows to other processes (``<mission>_<role>``)."""
    check: Callable[[str, object], str | None] | None = None
    """For a transport between processes: why a received message must be dropped
    (None: keep it), e.g. an action the mission's domain does not have."""


class TransportKind(ABC):
    """Base class of every transport plugin (group ``plansys_bridge.transports``)."""

    Settings: ClassVar[type[BaseModel]] = NoSettings
    """The ``transport:`` keys besides ``kind``."""
    distributed: ClassVar[bool] = False
    """Other processes can join the hub (``plansys-bridge performers``, remote peers)."""
    wall_clock_only: ClassVar[bool] = False
    """The virtual clock would expire protocol timeouts while messages travel."""

    def __init__(self, settings: BaseModel | None = None) -> None:
        self.settings = settings if settings is not None else self.Settings()

    @abstractmethod
    def create(self, context: TransportContext) -> Transport:
        """A new, not yet started transport; ConfigError(key=<setting>) for a bad setting."""

    @property
    def peer_timeout(self) -> float:
        """Seconds to wait for a heartbeat from each performer in another process."""
        return 10.0

    @property
    def dds_domain(self) -> int | None:
        """The DDS domain the messages travel in (None: not on DDS)."""
        return None


class InProcessKind(TransportKind):
    """Topics inside one process, delivered by the asyncio loop (the default)."""

    def create(self, context: TransportContext) -> Transport:
        return InProcessTransport()


class DdsSettings(PluginSettings):
    """Cyclone DDS, on 127.0.0.1 unless told otherwise: ``interfaces`` (addresses or
    names), ``peers`` (hosts to discover by unicast) and ``multicast`` describe a real
    network; ``config`` names a Cyclone XML file instead (what ``CYCLONEDDS_URI``
    would hold), for anything beyond that."""

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
    def _config_or_network(self) -> DdsSettings:
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


class DdsKind(TransportKind):
    """Cyclone DDS: performers may run in other processes and on other hosts."""

    Settings = DdsSettings
    distributed = True
    wall_clock_only = True
    settings: DdsSettings

    def create(self, context: TransportContext) -> Transport:
        try:
            from plansys_bridge.hub.dds import DdsTransport
        except ImportError as exc:
            raise ConfigError(
                f"the dds transport needs cyclonedds (pip install plansys-bridge[dds]): {exc}",
                key="kind",
            ) from exc
        return DdsTransport(
            self.settings.domain_id,
            config=self.cyclone_config(context.base_dir),
            check=context.check,
            node_name=context.node_name,
        )

    def cyclone_config(self, base_dir: Path) -> str:
        """The Cyclone XML of these settings (loopback unless configured)."""
        from plansys_bridge.hub.dds_config import network_config

        s = self.settings
        if s.config is not None:
            path = Path(s.config).expanduser()
            try:
                return read_text(path if path.is_absolute() else base_dir / path, "Cyclone DDS XML")
            except PlansysBridgeError as exc:
                raise ConfigError(str(exc), key="config") from exc
        return network_config(
            s.domain_id, interfaces=s.interfaces, peers=s.peer_list(), multicast=s.multicast
        )

    @property
    def peer_timeout(self) -> float:
        return self.settings.peer_timeout

    @property
    def dds_domain(self) -> int | None:
        return self.settings.domain_id


TRANSPORTS: PluginRegistry[TransportKind] = PluginRegistry(
    GROUPS["transports"],
    TransportKind,
    "transport",
    builtin={
        "inprocess": "plansys_bridge.hub.transport_kinds:InProcessKind",
        "dds": "plansys_bridge.hub.transport_kinds:DdsKind",
    },
)
"""The transport kinds installed (entry-point group ``plansys_bridge.transports``)."""


def transport_kind(name: str, settings: Any = None) -> TransportKind:
    """The transport kind ``name`` with ``settings`` validated (PluginError, ConfigError)."""
    from plansys_bridge.plugins import validate_settings

    cls = TRANSPORTS.load(name)
    return cls(validate_settings(cls.Settings, settings or {}))
