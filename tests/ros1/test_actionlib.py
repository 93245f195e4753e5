"""The actionlib client against rospy's SimpleActionServer (a move_base double)."""

from __future__ import annotations

import asyncio
from typing import Any

from plansys_bridge.ros1 import Node
from plansys_bridge.ros1.actionlib import ActionClient, GoalHandle, GoalStatus
from plansys_bridge.ros1.roscore import Roscore


def goal_to(node: Node, x: float, frame: str = "map") -> Any:
    goal = node.types.new("move_base_msgs/MoveBaseGoal")
    goal.target_pose.header.frame_id = frame
    goal.target_pose.pose.position.x = x
    goal.target_pose.pose.orientation.w = 1.0
    return goal


def test_goal_feedback_result_cancel_abort(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        await asyncio.to_thread(start_peer, "move_base_double.py", "/mb_a", "10")
        async with Node("action_test", master_uri=roscore.uri) as node:
            client = await ActionClient.create(node, "/mb_a", "move_base_msgs/MoveBase")
            assert await client.wait_for_server(20)
            seen: list[float] = []
            handle = client.send_goal(
                goal_to(node, 2.0), lambda fb: seen.append(fb.base_position.pose.position.x)
            )
            outcome = await handle.result()
            assert (outcome.status, outcome.text) == (GoalStatus.SUCCEEDED, "goal reached")
            assert seen and seen[-1] == 2.0 and seen == sorted(seen)

            handle = client.send_goal(goal_to(node, 40.0))
            while handle.status is not GoalStatus.ACTIVE:
                await asyncio.sleep(0.05)
            handle.cancel()
            outcome = await handle.result()
            assert (outcome.status, outcome.text) == (GoalStatus.PREEMPTED, "cancelled by client")

            outcome = await client.send_goal(goal_to(node, -60.0)).result()
            assert (outcome.status, outcome.text) == (GoalStatus.ABORTED, "no path to goal")
            await client.close()

    asyncio.run(main())


async def lose_goal(node: Node, ns: str, server: Any) -> tuple[ActionClient, GoalHandle]:
    """A goal running on ``server`` (a started peer), then the server killed: LOST."""
    client = await ActionClient.create(node, ns, "move_base_msgs/MoveBase", server_timeout=1.0)
    assert await client.wait_for_server(20)
    handle = client.send_goal(goal_to(node, 30.0))
    while handle.status is not GoalStatus.ACTIVE:
        await asyncio.sleep(0.05)
    await asyncio.to_thread(server.stop)
    outcome = await asyncio.wait_for(handle.result(), 20)
    assert outcome.status is GoalStatus.LOST
    assert "sent no status for 1 s" in outcome.text
    return client, handle


def test_server_that_dies_loses_the_goal(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        server = await asyncio.to_thread(start_peer, "move_base_double.py", "/mb_b", "0.5")
        async with Node("action_lost", master_uri=roscore.uri) as node:
            client, _handle = await lose_goal(node, "/mb_b", server)
            await client.close()

    asyncio.run(main())


def test_a_returning_server_is_told_to_cancel_the_lost_goal(
    roscore: Roscore, start_peer: Any
) -> None:
    async def main() -> None:
        server = await asyncio.to_thread(start_peer, "move_base_double.py", "/mb_c", "0.5")
        async with Node("action_back", master_uri=roscore.uri) as node:
            client, handle = await lose_goal(node, "/mb_c", server)
            assert list(client.abandoned) == [handle.goal_id]
            # the server comes back still driving that goal: it must be cancelled
            # not waiting for "ready": the cancel may come before it is printed
            back = await asyncio.to_thread(
                start_peer, "move_base_double.py", "/mb_c", "0.5", handle.goal_id, ready=False
            )
            await asyncio.to_thread(back.expect, "holding ")
            assert back.seen[0] == f"holding {handle.goal_id}"
            cancel = await asyncio.to_thread(back.expect, "cancel ")
            assert cancel == f"cancel {handle.goal_id}"
            assert await asyncio.to_thread(back.expect, "preempted") == "preempted"
            async with asyncio.timeout(20):  # PREEMPTED reported: nothing left to cancel
                while client.abandoned:
                    await asyncio.sleep(0.05)
            await client.close()

    asyncio.run(main())


def test_a_restarted_server_without_the_goal_lets_it_be_forgotten(
    roscore: Roscore, start_peer: Any
) -> None:
    """A move_base restarted from scratch never had the goal: it is told to cancel
    it once (actionlib lists it RECALLING) and the client stops asking."""

    async def main() -> None:
        server = await asyncio.to_thread(start_peer, "move_base_double.py", "/mb_d", "0.5")
        async with Node("action_fresh", master_uri=roscore.uri) as node:
            client, handle = await lose_goal(node, "/mb_d", server)
            # not waiting for "ready": the cancel may come before it is printed
            fresh = await asyncio.to_thread(
                start_peer, "move_base_double.py", "/mb_d", "0.5", ready=False
            )
            cancel = await asyncio.to_thread(fresh.expect, "cancel ")
            assert cancel == f"cancel {handle.goal_id}"
            async with asyncio.timeout(20):
                while client.abandoned:
                    await asyncio.sleep(0.05)
            await client.close()

    asyncio.run(main())
