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


def test_a_restarted_server_without_the_goal_lets_it_be_forgotten() -> None:
    """A Nav2 started afresh answers the cancel ERROR_UNKNOWN_GOAL_ID: the client
    stops asking (here the fresh server is the project's own Nav2 double)."""
    from plansys_bridge_adapters.ros2_nav2.double import NAV_TYPE, Nav2Double

    from plansys_bridge.interfaces.dds import dds_type
    from plansys_bridge.ros2.actions import STATUS_LOST, ActionClient
    from plansys_bridge.ros2.node import Ros2Node

    async def main() -> None:
        domain = random.SystemRandom().randint(1, 232)
        node = Ros2Node(domain, name="lost_goal_test")
        await node.start()
        client = ActionClient(node, "navigate_to_pose", NAV_TYPE, server_timeout=1.0)
        server = RawNavigateToPoseServer(domain)
        server.start()
        fresh = None
        try:
            await client.wait_for_server(20)
            goal = dds_type(f"{NAV_TYPE}_Goal")()
            goal.pose.pose.position.x = 30.0
            handle = await client.send_goal(goal)
            result = asyncio.ensure_future(handle.result())
            await _until(lambda: handle.goal_id in server.goals, 10, "the goal")
            await server.close()
            status, _ = await asyncio.wait_for(result, 20)
            assert status == STATUS_LOST and "gone for 1 s" in handle.text
            assert list(client.abandoned) == [handle.goal_id]
            fresh = await Nav2Double(domain).start()
            await _until(lambda: not client.abandoned, 20, "the unknown goal forgotten")
            assert fresh.goals == []
        finally:
            if fresh is not None:
                await fresh.close()
            await server.close()
            await client.close()
            await node.close()

    asyncio.run(main())
