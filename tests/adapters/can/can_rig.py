"""Test rig for the CAN adapter: a base double and the CAN performer on one virtual bus."""

from __future__ import annotations

import itertools
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from typing import Any

from plansys_bridge_adapters.can.bus import BusConfig
from plansys_bridge_adapters.can.double import BaseDouble, BaseDoubleConfig
from plansys_bridge_adapters.can.performer import CanBasePerformer

from plansys_bridge.clock import Clock
from plansys_bridge.hub.hub import Hub
from plansys_bridge.performers.base import PerformerContext

_channels = itertools.count(1)

LOCATIONS: dict[str, Any] = {
    "dock": [0.0, 0.0, 0.0],
    "kitchen": {"x": 2.0, "y": 1.0},
    "bedroom": {"x": 0.5, "y": 2.5, "yaw": 1.57, "via": [[1.5, 2.0]]},
    "hall": [1.0, 0.0],
}


def new_channel() -> str:
    """A virtual channel name no other test uses."""
    return f"can-test-{next(_channels)}"


def base_entry(channel: str, **overrides: Any) -> dict[str, Any]:
    """A mission-file performer entry for the base ``r2d2`` on ``channel``."""
    entry: dict[str, Any] = {
        "kind": "can",
        "name": "base_r2d2",
        "robot": "r2d2",
        "actions": {"move": {"robot": 0, "destination": 2}},
        "locations": LOCATIONS,
        "bus": {"interface": "virtual", "channel": channel},
    }
    entry.update(overrides)
    return entry


@dataclass
class Rig:
    hub: Hub
    performer: CanBasePerformer
    double: BaseDouble

    @property
    def clock(self) -> Clock:
        return self.hub.clock


@asynccontextmanager
async def can_rig(
    hub: Hub,
    channel: str,
    *,
    double: BaseDoubleConfig | None = None,
    knowledge: object | None = None,
    **entry: Any,
) -> AsyncIterator[Rig]:
    """Base double + CAN performer on ``channel``, both started; stopped on exit."""
    await hub.start()
    bus = entry.get("bus", {"interface": "virtual", "channel": channel})
    base = BaseDouble(
        hub.clock, BusConfig(interface=bus["interface"], channel=bus["channel"]), double
    )
    await base.start()
    context = PerformerContext(hub=hub, clock=hub.clock, knowledge=knowledge)  # type: ignore[arg-type]
    [performer] = CanBasePerformer.from_config(base_entry(channel, **entry), context)
    assert isinstance(performer, CanBasePerformer)
    await performer.start()
    try:
        yield Rig(hub, performer, base)
    finally:
        await performer.stop()
        await base.stop()
        await hub.close()
