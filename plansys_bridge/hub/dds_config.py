"""A Cyclone DDS configuration that keeps all traffic on the loopback interface.

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

from xml.sax.saxutils import quoteattr

from plansys_bridge.errors import ConfigError

__all__ = ["MAX_DOMAIN_ID", "check_domain_id", "loopback_config"]

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
    domain = "any" if domain_id is None else str(check_domain_id(domain_id))
    if not 1 <= max_participants <= 100:
        raise ConfigError(
            f"max_participants must be within 1..100, got {max_participants}",
            key="max_participants",
        )
    addr = quoteattr(address)
    return (
        '<CycloneDDS xmlns="https://cdds.io/config">'
        f'<Domain Id="{domain}">'
        "<General>"
        f'<Interfaces><NetworkInterface address={addr} multicast="false"/></Interfaces>'
        "<AllowMulticast>false</AllowMulticast>"
        "<DontRoute>true</DontRoute>"
        "</General>"
        "<Discovery>"
        "<ParticipantIndex>auto</ParticipantIndex>"
        f"<MaxAutoParticipantIndex>{max_participants - 1}</MaxAutoParticipantIndex>"
        f"<Peers><Peer address={addr}/></Peers>"
        "</Discovery>"
        # A closing writer waits this long for unacknowledged data: plenty on loopback,
        # and a peer that died without leaving does not hold the shutdown for seconds.
        "<Internal><WriterLingerDuration>100 ms</WriterLingerDuration></Internal>"
        "</Domain>"
        "</CycloneDDS>"
    )
