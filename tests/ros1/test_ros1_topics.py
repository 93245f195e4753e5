"""The project's ROS 1 node against Debian's roscore and rospy peers."""

from __future__ import annotations

import asyncio
import logging
import socket
from typing import Any

import pytest

from plansys_bridge.ros1 import Node
from plansys_bridge.ros1.roscore import Roscore
from plansys_bridge.ros1.tcpros import encode_header


async def wait_until(check: Any, timeout: float = 20.0) -> None:
    async with asyncio.timeout(timeout):
        while not check():
            await asyncio.sleep(0.05)


def test_publisher_to_rospy_listener_latched(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        async with Node("pub_test", master_uri=roscore.uri) as node:
            pub = await node.advertise("/chatter_latched", "std_msgs/String", latch=True)
            pub.publish(node.types.new("std_msgs/String", data="before anyone listened"))
            listener = await asyncio.to_thread(
                start_peer, "listener.py", "/chatter_latched", "String"
            )
            await pub.wait_for_subscribers(1, timeout=20)
            line = await asyncio.to_thread(listener.expect, "got")
            assert line == "got before anyone listened"
            for i in range(3):
                pub.publish(node.types.new("std_msgs/String", data=f"n{i}"))
            for i in range(3):
                assert await asyncio.to_thread(listener.expect, "got") == f"got n{i}"
            publishers, subscribers, _ = await node.master.system_state()
            assert node.name in publishers["/chatter_latched"]
            assert len(subscribers["/chatter_latched"]) == 1

    asyncio.run(main())


def test_rospy_talker_to_subscriber_odometry(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        async with Node("sub_test", master_uri=roscore.uri) as node:
            got: list[Any] = []
            sub = await node.subscribe("/odom_in", "nav_msgs/msg/Odometry", got.append)
            await asyncio.to_thread(start_peer, "talker.py", "/odom_in", "Odometry", "50")
            await wait_until(lambda: len(got) >= 5)
            first, last = got[0], got[-1]
            assert first.header.frame_id == "odom" and first.child_frame_id == "base_link"
            assert last.pose.pose.position.x > first.pose.pose.position.x
            assert last.header.seq > first.header.seq
            assert sub.num_connections == 1

    asyncio.run(main())


def test_master_params_and_lookup(roscore: Roscore) -> None:
    async def main() -> None:
        async with Node("param_test", master_uri=roscore.uri) as node:
            await node.master.set_param("/plansys/speed", 1.5)
            assert await node.master.get_param("/plansys/speed") == 1.5
            assert await node.master.has_param("/plansys/speed")
            await node.master.delete_param("/plansys/speed")
            assert not await node.master.has_param("/plansys/speed")
            await node.advertise("/param_test_topic", "std_msgs/String")
            assert await node.master.lookup_node(node.name) == node.uri

    asyncio.run(main())


def test_type_mismatch_is_refused_naming_both(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        async with Node("mismatch", master_uri=roscore.uri) as node:
            await node.advertise("/typed", "std_msgs/String")
            got: list[Any] = []
            async with Node("mismatch_sub", master_uri=roscore.uri) as other:
                sub = await other.subscribe("/typed", "nav_msgs/Odometry", got.append)
                await asyncio.sleep(1.0)
                assert sub.num_connections == 0 and not got

    asyncio.run(main())


def test_malformed_header_drops_one_connection(
    roscore: Roscore, start_peer: Any, caplog: pytest.LogCaptureFixture
) -> None:
    async def main() -> None:
        async with Node("robust", master_uri=roscore.uri) as node:
            pub = await node.advertise("/robust", "std_msgs/String")
            listener = await asyncio.to_thread(start_peer, "listener.py", "/robust", "String")
            await pub.wait_for_subscribers(1, timeout=20)
            # A peer that sends garbage instead of a connection header.
            reader, writer = await asyncio.open_connection("127.0.0.1", node.tcp_port)
            writer.write(b"\x08\x00\x00\x00\x04\x00\x00\x00abcd")
            await writer.drain()
            assert await reader.read() == b""  # the node closed it
            writer.close()
            # A peer asking for a topic the node does not publish gets an error header.
            reader, writer = await asyncio.open_connection("127.0.0.1", node.tcp_port)
            writer.write(encode_header({"topic": "/nope", "md5sum": "*", "callerid": "/x"}))
            assert b"error=" in await reader.read()
            writer.close()
            pub.publish(node.types.new("std_msgs/String", data="still here"))
            assert await asyncio.to_thread(listener.expect, "got") == "got still here"

    with caplog.at_level(logging.WARNING):
        asyncio.run(main())
    text = caplog.text
    assert "malformed connection header from 127.0.0.1:" in text
    assert "not key=value" in text
    assert "/nope" in text


def test_malformed_frame_drops_that_publisher_only(
    roscore: Roscore, start_peer: Any, caplog: pytest.LogCaptureFixture
) -> None:
    async def main() -> None:
        async with (
            Node("bad_pub", master_uri=roscore.uri) as bad,
            Node("good_sub", master_uri=roscore.uri) as node,
        ):
            got: list[Any] = []
            sub = await node.subscribe("/mixed", "std_msgs/String", got.append)
            pub = await bad.advertise("/mixed", "std_msgs/String")
            await asyncio.to_thread(start_peer, "talker.py", "/mixed", "String", "20")
            await wait_until(lambda: sub.num_connections == 2)
            pub.publish_raw(b"\xff\xff\xff\x7fnot a string")
            await wait_until(lambda: sub.num_connections == 1)
            count = len(got)
            await wait_until(lambda: len(got) > count + 3)
            assert all(m.data.startswith("hello") for m in got)

    with caplog.at_level(logging.WARNING):
        asyncio.run(main())
    assert "ROS 1 topic /mixed: malformed message from /bad_pub_" in caplog.text
    assert "connection dropped" in caplog.text


def test_node_binds_loopback_by_default(roscore: Roscore) -> None:
    async def main() -> None:
        async with Node("bind_test", master_uri=roscore.uri) as node:
            assert node.bind == "127.0.0.1"
            with socket.create_connection(("127.0.0.1", node.tcp_port), timeout=5):
                pass

    asyncio.run(main())
