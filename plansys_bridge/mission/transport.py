"""The clock and the hub transport a mission file names.

In-process unless ``transport: {kind: dds}``; DDS (and its cyclonedds import) only
then, with the loopback configuration unless the file gives another, and signed
messages when ``auth:`` names a fleet key.
"""

from __future__ import annotations

from collections.abc import Set

from plansys_bridge.clock import Clock, VirtualClock, WallClock
from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.hub.transport import InProcessTransport, Transport
from plansys_bridge.mission.file_keys import keyed
from plansys_bridge.mission_config import MissionConfig
from plansys_bridge.pddl.model import Domain
from plansys_bridge.textfile import read_text

__all__ = ["make_clock", "make_transport"]


def make_clock(mission: MissionConfig) -> Clock:
    if mission.clock.kind == "virtual":
        return VirtualClock()
    return WallClock(time_scale=mission.clock.time_scale)


def make_transport(
    mission: MissionConfig,
    domain: Domain | None = None,
    role: str = "executor",
    plan_ids: Set[str] | None = None,
) -> Transport:
    """The hub transport the mission's ``transport:`` names (DDS imported only then),
    signed with the fleet key when ``auth:`` gives one (:mod:`plansys_bridge.hub.auth`).

    With ``domain``, a DDS transport drops received messages about actions the domain
    does not have (:func:`~plansys_bridge.hub.dds_checks.domain_check`), and with
    ``plan_ids`` (filled as plans start) those about a plan this process does not
    execute. Over DDS the
    process shows to ROS 2 tools as the node ``<mission name>_<role>``.
    """
    transport = _bare_transport(mission, domain, role, plan_ids)
    if mission.auth is None:
        return transport
    from plansys_bridge.hub.auth import AuthTransport, load_key

    with keyed(mission, "auth.key_file"):
        key = load_key(mission.resolve(mission.auth.key_file))
    return AuthTransport(transport, key, window=mission.auth.window)


def _bare_transport(
    mission: MissionConfig, domain: Domain | None, role: str, plan_ids: Set[str] | None
) -> Transport:
    if mission.transport.kind == "dds":
        try:
            from plansys_bridge.hub.dds import DdsTransport
            from plansys_bridge.hub.dds_checks import domain_check
        except ImportError as exc:
            raise ConfigError(
                f"the dds transport needs cyclonedds (pip install plansys-bridge[dds]): {exc}",
                key="transport.kind",
                file=mission.source,
            ) from exc
        check = None
        if domain is not None:
            actions = {a.name: len(a.parameters) for a in domain.actions}
            check = domain_check(actions, plan_ids)
        return DdsTransport(
            mission.transport.domain_id,
            config=_dds_config(mission),
            check=check,
            node_name=f"{mission.name}_{role}",
        )
    return InProcessTransport()


def _dds_config(mission: MissionConfig) -> str:
    """The Cyclone XML for the mission's ``transport:`` (loopback unless configured)."""
    from plansys_bridge.hub.dds_config import network_config

    t = mission.transport
    if t.config is not None:
        try:
            return read_text(mission.resolve(t.config), "Cyclone DDS XML")
        except PlansysBridgeError as exc:
            raise ConfigError(str(exc), key="transport.config", file=mission.source) from exc
    try:
        return network_config(
            t.domain_id, interfaces=t.interfaces, peers=t.peer_list(), multicast=t.multicast
        )
    except ConfigError as exc:
        raise ConfigError(
            str(exc).split(": ", 1)[-1], key=f"transport.{exc.key}", file=mission.source
        ) from exc
