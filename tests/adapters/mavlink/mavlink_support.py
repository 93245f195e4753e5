"""Helpers shared by the MAVLink adapter tests (imported as ``mavlink_support``)."""

from __future__ import annotations

import socket
from pathlib import Path
from typing import Any, Literal

from plansys_bridge_adapters.mavlink.performer import MavlinkPerformer

from plansys_bridge.clock import WallClock
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext

SPEEDUP = 40.0
"""Doubles run this much faster than real time: a whole mission takes about a second."""
REPO = Path(__file__).resolve().parents[3]
CONFIGS = REPO / "configs"


def free_port(transport: Literal["tcp", "udp"] = "tcp") -> int:
    """A loopback port nothing listens on right now (the OS picks it)."""
    kind = socket.SOCK_STREAM if transport == "tcp" else socket.SOCK_DGRAM
    with socket.socket(socket.AF_INET, kind) as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def make_hub() -> Hub:
    return Hub(InProcessTransport(), WallClock())


COPTER_ACTIONS: dict[str, list[str]] = {"takeoff": [], "fly": [], "land": [], "rtl": [], "hold": []}
COPTER_COMMANDS = {
    "takeoff": {"do": "takeoff", "vehicle_arg": 0, "altitude": 10},
    "fly": {"do": "goto", "vehicle_arg": 0, "target_arg": 2},
    "land": {"do": "land", "vehicle_arg": 0},
    "rtl": {"do": "rtl", "vehicle_arg": 0},
    "hold": {"do": "hold", "vehicle_arg": 0},
}
ROVER_ACTIONS: dict[str, list[str]] = {"drive": [], "hold": [], "rtl": [], "land": []}
ROVER_COMMANDS = {
    "drive": {"do": "goto", "vehicle_arg": 0, "target_arg": 2},
    "hold": {"do": "hold", "vehicle_arg": 0},
    "rtl": {"do": "rtl", "vehicle_arg": 0},
    "land": {"do": "land", "vehicle_arg": 0},
}


def performer_config(vehicle: str, url: str, model: str, **extra: Any) -> dict[str, Any]:
    """A mission-file performer entry for ``vehicle`` on ``url``."""
    copter = model == "copter"
    config: dict[str, Any] = {
        "kind": "mavlink",
        "name": f"{vehicle}_performer",
        "vehicle": vehicle,
        "model": model,
        "url": url,
        "locations": "mavlink_locations.yaml",
        "actions": dict(COPTER_ACTIONS if copter else ROVER_ACTIONS),
        "commands": dict(COPTER_COMMANDS if copter else ROVER_COMMANDS),
        "heartbeat_period": 0.2,
        "feedback_period": 0.02,
        "timeouts": {"heartbeat": 1.0, "command": 0.5, "ekf": 20, "arm": 10, "action": 30},
    }
    config.update(extra)
    return config


def build(config: dict[str, Any], hub: Hub, knowledge: Any = None) -> MavlinkPerformer:
    context = PerformerContext(hub=hub, clock=hub.clock, knowledge=knowledge, base_dir=CONFIGS)
    [performer] = MavlinkPerformer.from_config(config, context, key="performers[0]")
    assert isinstance(performer, MavlinkPerformer)
    return performer
