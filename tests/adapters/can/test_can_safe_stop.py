"""The base's safe state when its performer stops mid-move (the end of a mission, an
abort, SIGINT/SIGTERM of ``plansys-bridge run``): zero velocity until the twist shows
standstill, then the stop frame (zero velocity, drive disabled) on the bus, against
the base double on python-can's virtual bus (virtual time)."""

from __future__ import annotations

import asyncio
import math

from can_rig import Rig, can_rig

from plansys_bridge.clock import run
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub


def test_stopping_the_performer_mid_move_stops_the_base(hub: Hub, channel: str) -> None:
    async def main() -> None:
        async with can_rig(hub, channel) as rig:
            await _stop_mid_move(rig)

    run(main(), hub.clock)


async def _stop_mid_move(rig: Rig) -> None:
    client = ActionClient(rig.hub, "move", ["r2d2", "dock", "kitchen"])
    task = asyncio.get_running_loop().create_task(client.run())
    await rig.clock.sleep(2.0)
    assert rig.double.model.moving
    await rig.performer.stop()  # what the mission does on its way out
    await rig.clock.sleep(1.0)
    assert not rig.double.model.moving
    last = rig.double.last_command
    assert last is not None and (last.linear, last.angular) == (0.0, 0.0)
    assert last.enable is False  # the stop frame, not merely a zero set-point
    assert rig.double.counters.estop_commands == 0
    # it stopped where it was, short of the kitchen
    assert math.hypot(rig.double.model.x - 2.0, rig.double.model.y - 1.0) > 0.3
    client.cancel()
    await task
