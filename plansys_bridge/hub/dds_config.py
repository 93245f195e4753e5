"""Cyclone DDS configurations: loopback only (the default), or a deployment's network.

Without a configuration Cyclone DDS multicasts discovery on the first network
interface it finds. The hub's processes run on one machine, so the configuration
pins Cyclone to ``127.0.0.1``, turns multicast off, and finds the other processes by
unicast discovery on the same address. Unicast discovery needs predictable ports:
with ``ParticipantIndex auto`` each process takes the first free participant index
(its ports are 7410 + 250 * domain + 2 * index, +1 for data), and discovery probes
indices ``0 .. max_participants - 1`` on 127.0.0.1.

The text is what ``CYCLONEDDS_URI`` would hold; :class:`~plansys_bridge.hub.dds.DdsTransport`
passes it straight to ``cyclonedds.domain.Domain(domain_id, config)``.
"""

from __future__ import annotations

import ipaddress
import re
from collections.abc import Sequence
from xml.sax.saxutils import quoteattr

from plansys_bridge.errors import ConfigError

__all__ = ["MAX_DOMAIN_ID", "check_domain_id", "loopback_config", "network_config"]

_NAME = re.compile(r"^[A-Za-z0-9_.:@-]{1,15}$")
"""A Linux network interface name (at most 15 characters)."""

MAX_DOMAIN_ID = 232
"""The largest domain id whose RTPS ports (7400 + 250 * id + ...) fit below 65536."""


def check_domain_id(domain_id: int) -> int:
    if isinstance(domain_id, bool) or not isinstance(domain_id, int):
        raise ConfigError(f"domain_id must be an integer, got {domain_id!r}", key="domain_id")
    if not 0 <= domain_id <= MAX_DOMAIN_ID:
        raise ConfigError(
            f"domain_id must be within 0..{MAX_DOMAIN_ID}, got {domain_id}", key="domain_id"
        )
    return domain_id


def loopback_config(
    domain_id: int | None = None,
    *,
    address: str = "127.0.0.1",
    max_participants: int = 20,
) -> str:
    """Cyclone DDS XML for ``address`` only: no multicast, unicast discovery on ``address``.

    ``domain_id`` restricts the configuration to that domain (``None``: any domain).
    ``max_participants`` is how many processes of one domain can find each other.
    """
    return network_config(
        domain_id, interfaces=[address], peers=[address], max_participants=max_participants
    )


def _interface(value: str) -> str:
    """``<NetworkInterface>`` by address (``192.168.1.5``) or by name (``eth0``)."""
    try:
        address = ipaddress.ip_address(value)
    except ValueError:
        if not _NAME.match(value):
            raise ConfigError(
                f"{value!r} is neither an IP address nor a network interface name",
                key="interfaces",
            ) from None
        return f"name={quoteattr(value)}"
    return f"address={quoteattr(str(address))}"


def _peer(value: str) -> str:
    """A peer is an address or host name, optionally with a port (``host:7410``)."""
    if not value or any(c.isspace() for c in value) or "<" in value:
        raise ConfigError(f"{value!r} is not a host name or address", key="peers")
    return f"<Peer address={quoteattr(value)}/>"


def network_config(
    domain_id: int | None = None,
    *,
    interfaces: Sequence[str] = ("127.0.0.1",),
    peers: Sequence[str] = (),
    multicast: bool = False,
    max_participants: int = 20,
) -> str:
    """Cyclone DDS XML for a deployment: which interfaces, which peers, multicast or not.

    ``interfaces`` are addresses or interface names this process uses (Cyclone picks
    among them); ``peers`` are the hosts unicast discovery contacts (their participant
    indices ``0 .. max_participants - 1`` are probed); ``multicast`` turns on SPDP
    multicast discovery and multicast data on those interfaces. A robot and a base
    station meet when each lists the other as a peer (or both enable multicast on a
    shared network); neither alone, by default, leaves the machine.
    """
    domain = "any" if domain_id is None else str(check_domain_id(domain_id))
    if not 1 <= max_participants <= 100:
        raise ConfigError(
            f"max_participants must be within 1..100, got {max_participants}",
            key="max_participants",
        )
    if not interfaces:
        raise ConfigError("at least one network interface is needed", key="interfaces")
    on = "true" if multicast else "false"
    nics = "".join(f'<NetworkInterface {_interface(i)} multicast="{on}"/>' for i in interfaces)
    loopback_only = all(_is_loopback(i) for i in interfaces)
    peer_xml = "".join(_peer(p) for p in peers)
    return (
        '<CycloneDDS xmlns="https://cdds.io/config">'
        f'<Domain Id="{domain}">'
        "<General>"
        f"<Interfaces>{nics}</Interfaces>"
        f"<AllowMulticast>{on}</AllowMulticast>"
        + ("<DontRoute>true</DontRoute>" if loopback_only else "")
        + "</General>"
        "<Discovery>"
        "<ParticipantIndex>auto</ParticipantIndex>"
        f"<MaxAutoParticipantIndex>{max_participants - 1}</MaxAutoParticipantIndex>"
        + (f"<Peers>{peer_xml}</Peers>" if peer_xml else "")
        + "</Discovery>"
        # A closing writer waits this long for unacknowledged data: plenty on loopback,
        # and a peer that died without leaving does not hold the shutdown for seconds.
        "<Internal><WriterLingerDuration>100 ms</WriterLingerDuration></Internal>"
        "</Domain>"
        "</CycloneDDS>"
    )


def _is_loopback(value: str) -> bool:
    try:
        return ipaddress.ip_address(value).is_loopback
    except ValueError:
        return value == "lo"
