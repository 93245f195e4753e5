"""A Nav2 server that vanishes mid-goal fails the action LOST, and when it comes back
still driving that goal the client cancels it, so the robot does not resume an
action the executor gave up (issue 20). The server is the independent
NavigateToPose server of tests/nav2_peer.py (plain Cyclone DDS)."""

import asyncio
import random

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from nav2_peer import RawNavigateToPoseServer
from plansys_bridge_adapters.ros2_nav2.performer import Nav2Performer
from ros2_upstream import CANCELED
from test_ros2_nav2 import _entry, _finish, _knowledge
from test_ros2_nav2_safe_stop import _until

from plansys_bridge.clock import WallClock
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.performers.base import PerformerContext

pytestmark = [pytest.mark.timeout(120), pytest.mark.usefixtures("no_leaks")]


def test_a_returning_server_is_told_to_cancel_the_lost_goal() -> None:
    async def main() -> tuple[bytes, RawNavigateToPoseServer]:
        domain = random.SystemRandom().randint(1, 232)
        hub = Hub(clock=WallClock())
        await hub.start()
        seen: list[ActionExecution] = []
        hub.subscribe(Topics.ACTIONS_HUB, seen.append)
        context = PerformerContext(hub, hub.clock, knowledge=_knowledge())
        (performer,) = Nav2Performer.from_config(_entry(domain), context)
        assert isinstance(performer, Nav2Performer)
        performer.lost_after = 1.0
        await performer.start()
        server = RawNavigateToPoseServer(domain)
        server.start()
        back = None
        try:
            await _until(lambda: performer.ready, 20, "the performer to see Nav2")
            for kind in (ExecutionType.REQUEST, ExecutionType.CONFIRM):
                node = "" if kind is ExecutionType.REQUEST else "tb3"
                args = ("r1", "hall", "garden")  # runs until cancelled
                hub.publish(
                    Topics.ACTIONS_HUB, ActionExecution(kind, node, "move", args, request_id="g")
                )
                await asyncio.sleep(0.01)
            await _until(lambda: server.goals, 10, "the goal")
            (gid,) = server.goals
            await server.close()  # Nav2 drops off the network mid-goal
            finish = await _finish(seen, "g")
            assert not finish.success
            assert finish.status.startswith("/navigate_to_pose LOST the goal to garden:")
            client = performer._client
            assert client is not None and list(client.abandoned) == [gid]
            assert server.cancels == []
            back = RawNavigateToPoseServer(domain)
            back.hold(gid, 30.0)  # ... and comes back still driving it
            back.start()
            await _until(lambda: back.cancels, 20, "the cancel of the lost goal")
            await _until(lambda: not client.abandoned, 10, "the cancelled goal forgotten")
        finally:
            await performer.stop()
            await server.close()
            if back is not None:
                await back.close()
            await hub.close()
        return gid, back

    gid, back = asyncio.run(main())
    assert back.cancels == [gid]
    assert back.goals[gid]["status"] == CANCELED
