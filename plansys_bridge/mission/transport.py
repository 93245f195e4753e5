"""The clock and the hub transport a mission file names.

The transport is the plugin ``transport: {kind: ...}`` names
(:mod:`plansys_bridge.hub.transport_kinds`): in-process by default, DDS (and its
cyclonedds import) only when asked for; messages are signed when ``auth:`` names a
fleet key.
"""

from __future__ import annotations

from collections.abc import Set

from plansys_bridge.clock import Clock, VirtualClock, WallClock
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.transport import Transport
from plansys_bridge.mission.file_keys import keyed
from plansys_bridge.mission_config import MissionConfig
from plansys_bridge.pddl.model import Domain

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
    """The hub transport the mission's ``transport:`` names, signed with the fleet
    key when ``auth:`` gives one (:mod:`plansys_bridge.hub.auth`).

    With ``domain``, a transport between processes drops received messages about
    actions the domain does not have (:func:`~plansys_bridge.hub.dds_checks.domain_check`),
    and with ``plan_ids`` (filled as plans start) those about a plan this process does
    not execute. Other processes see this one as ``<mission name>_<role>`` (over DDS,
    the ROS 2 node name).
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
    """The transport plugin's transport; its errors name the ``transport:`` key."""
    from plansys_bridge.hub.transport_kinds import TransportContext

    kind = mission.transport_kind()
    check = None
    if domain is not None and kind.distributed:
        from plansys_bridge.hub.dds_checks import domain_check

        actions = {a.name: len(a.parameters) for a in domain.actions}
        check = domain_check(actions, plan_ids)
    context = TransportContext(mission.base_dir, f"{mission.name}_{role}", check)
    try:
        return kind.create(context)
    except ConfigError as exc:
        raise mission.error(exc.reason, key=f"transport.{exc.key}".rstrip(".")) from exc
