"""The project's own ROS master with rospy peers (Debian's rospy, /usr/bin/python3)."""

from __future__ import annotations

import asyncio
from typing import Any

from plansys_bridge.ros1 import Node
from plansys_bridge.ros1.roscore import ros_env
from plansys_bridge.ros1.rosmaster import Master


def test_rospy_and_the_project_meet_through_the_project_master(
    ros1_available: None, start_peer: Any
) -> None:
    with Master(port=0) as master:
        env = ros_env(master.uri.rstrip("/"))
        listener = start_peer("listener.py", "/chatter", "String", env=env)
        start_peer("talker.py", "/odom_m", "Odometry", "20", env=env)

        async def main() -> None:
            async with Node("with_own_master", master_uri=master.uri) as node:
                got: list[Any] = []
                await node.subscribe("/odom_m", "nav_msgs/Odometry", got.append)
                pub = await node.advertise("/chatter", "std_msgs/String")
                await pub.wait_for_subscribers(1, timeout=30)
                pub.publish(node.types.new("std_msgs/String", data="via our master"))
                async with asyncio.timeout(30):
                    while len(got) < 3:
                        await asyncio.sleep(0.05)
                publishers, subscribers, services = await node.master.system_state()
                assert node.name in publishers["/chatter"]
                assert node.name in subscribers["/odom_m"]
                assert any(name.endswith("/get_loggers") for name in services)  # rospy's
                await node.master.set_param("/robot/speed", 0.5)
                assert await node.master.get_param("/robot") == {"speed": 0.5}

        asyncio.run(main())
        assert listener.expect("got") == "got via our master"


def test_master_parameters_and_unknown_nodes() -> None:
    with Master(port=0) as master:

        async def main() -> None:
            async with Node("params", master_uri=master.uri) as node:
                await node.master.set_param("/a", {"b": 1, "c": {"d": "x"}})
                assert await node.master.get_param("/a/c/d") == "x"
                assert sorted(await node.master.param_names()) == ["/a/b", "/a/c/d"]
                await node.master.delete_param("/a/c")
                assert not await node.master.has_param("/a/c/d")
                assert await node.master.has_param("/a/b")
                try:
                    await node.master.lookup_node("/nobody")
                except Exception as exc:
                    assert "unknown node [/nobody]" in str(exc)
                else:
                    raise AssertionError("lookupNode of an unknown node succeeded")

        asyncio.run(main())
