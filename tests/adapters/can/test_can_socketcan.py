"""The CAN performer on a kernel SocketCAN interface, when one is offered.

This machine's kernel has no SocketCAN, so the test is skipped unless
``PLANSYS_BRIDGE_SOCKETCAN`` names an interface that is up, e.g. a virtual one::

    sudo modprobe vcan && sudo ip link add dev vcan0 type vcan && sudo ip link set vcan0 up
    PLANSYS_BRIDGE_SOCKETCAN=vcan0 pytest tests/adapters/can/test_can_socketcan.py

The base double and the performer open their own sockets on the interface (the
kernel loops frames back between sockets), on the wall clock, so the performer's
reader is the event loop watching its socket.
"""

from __future__ import annotations

import math
import os

import pytest
from can_rig import Rig, can_rig

from plansys_bridge.clock import WallClock, run
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport

INTERFACE = os.environ.get("PLANSYS_BRIDGE_SOCKETCAN", "")


@pytest.mark.skipif(
    not INTERFACE,
    reason="set PLANSYS_BRIDGE_SOCKETCAN to a SocketCAN interface that is up (e.g. vcan0)",
)
def test_move_and_fault_on_socketcan() -> None:
    hub = Hub(InProcessTransport(), WallClock(time_scale=0.5))

    async def main() -> None:
        bus = {"interface": "socketcan", "channel": INTERFACE}
        async with can_rig(hub, INTERFACE, bus=bus) as rig:
            await scenario(rig)

    async def scenario(rig: Rig) -> None:
        assert rig.performer.client.bus is not None
        outcome = await ActionClient(rig.hub, "move", ["r2d2", "dock", "hall"]).run()
        assert outcome.success, outcome.status
        assert math.hypot(rig.double.model.x - 1.0, rig.double.model.y) <= 0.05
        rig.double.set_faults(overcurrent=True)
        outcome = await ActionClient(rig.hub, "move", ["r2d2", "hall", "dock"]).run()
        assert "base fault: overcurrent" in outcome.status

    run(main(), hub.clock)
