"""A move_base goal never outlives its performer: stopping it mid-goal (the end of a
mission, an abort, SIGINT/SIGTERM of ``plansys-bridge run``) preempts the goal on
rospy's actionlib move_base double."""

from __future__ import annotations

import asyncio
from typing import Any

from test_move_base_performer import ready_performer

from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.ros1.roscore import Roscore


def test_stopping_the_performer_preempts_the_goal(roscore: Roscore, start_peer: Any) -> None:
    double = start_peer("move_base_double.py", "/tiago_mb_stop", "1")

    async def main() -> None:
        async with ready_performer(roscore.uri, "/tiago_mb_stop") as (hub, p):
            client = ActionClient(hub, "move", ("tiago", "kitchen", "bedroom"))
            task = asyncio.ensure_future(client.run())
            while p.completion <= 0.0:
                await asyncio.sleep(0.05)
            await p.stop()  # what the mission does on its way out
            client.cancel()
            await task

    asyncio.run(main())
    assert double.expect("preempted") == "preempted"
