"""Performers in one process, executor in another, joined by a distributed hub (DDS).

Two halves of ``transport: {kind: dds}`` missions:

* :func:`serve_performers` (``plansys-bridge performers MISSION.yaml``) builds and
  starts only the mission's performers on the hub and serves auctions until stopped;
* :func:`wait_for_performers` (``plansys-bridge run MISSION.yaml --no-performers``)
  lets the executor side wait for a heartbeat from every performer the mission
  names before planning, so a missing process is an error naming it instead of
  actions that never find a performer.

The performer process reads the same mission file: its knowledge is built from the
file for adapters that consult it, but changes made there stay in that process (the
executor's knowledge is the one that plans).
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Sequence

from plansys_bridge.errors import HubError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionPerformerStatus, Topics
from plansys_bridge.performers.base import ActionPerformer, PerformerContext
from plansys_bridge.performers.registry import performers_from_config, start_performers

__all__ = ["serve_performers", "wait_for_performers"]

log = logging.getLogger(__name__)


async def wait_for_performers(
    hub: Hub, names: Sequence[str], *, timeout: float, where: str = "mission"
) -> None:
    """Return once each of ``names`` sent a heartbeat; HubError naming the missing ones."""
    missing = set(names)
    if not missing:
        return
    all_seen = asyncio.get_running_loop().create_future()

    def on_status(msg: object) -> None:
        if isinstance(msg, ActionPerformerStatus):
            missing.discard(msg.node_name)
            if not missing and not all_seen.done():
                all_seen.set_result(None)

    sub = hub.subscribe(Topics.PERFORMERS_STATUS, on_status)
    try:
        await asyncio.wait_for(all_seen, timeout)
    except TimeoutError as exc:
        raise HubError(
            f"{where}: no heartbeat from performer(s) {', '.join(sorted(missing))} after "
            f"{timeout:g} s on {hub.transport!r} (start them with "
            "`plansys-bridge performers MISSION.yaml`)"
        ) from exc
    finally:
        sub.close()


async def serve_performers(
    context: PerformerContext,
    entries: Sequence[dict[str, object]],
    until: Awaitable[object],
    *,
    on_ready: Callable[[list[ActionPerformer]], None] | None = None,
    say: Callable[[str], None] | None = None,
) -> list[ActionPerformer]:
    """Start the performers of ``entries`` on ``context.hub``, serve until ``until`` is done.

    The hub must be started; it stays open (the caller owns it). Performers are
    stopped in reverse order whatever happens, so the executor sees their final
    status before the process leaves the domain.
    """
    performers = performers_from_config(entries, context)
    started = await start_performers(performers, say)
    try:
        if on_ready is not None:
            on_ready(started)
        await until
    finally:
        for performer in reversed(started):
            try:
                await performer.stop()
            except Exception:  # a broken adapter must not keep the others running
                log.exception("stopping performer %s failed", performer.node_name)
    return started
