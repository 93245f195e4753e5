"""Master down and back, publishers that vanish and return (real roscore and rospy)."""

from __future__ import annotations

import asyncio
import logging
from pathlib import Path
from typing import Any

import pytest

from plansys_bridge.ros1 import MasterUnreachable, Node
from plansys_bridge.ros1.roscore import Roscore, free_port


async def wait_until(check: Any, timeout: float = 30.0) -> None:
    async with asyncio.timeout(timeout):
        while not check():
            await asyncio.sleep(0.05)


def test_unreachable_master_is_one_clear_error(
    ros1_available: None, caplog: pytest.LogCaptureFixture
) -> None:
    uri = f"http://127.0.0.1:{free_port()}"

    async def main() -> None:
        async with Node("lonely", master_uri=uri, watch_period=0.1) as node:
            await node.advertise("/x", "std_msgs/String")
            with pytest.raises(MasterUnreachable, match=f"no ROS master answers at {uri}"):
                await node.wait_for_master(timeout=0.5)
            assert node.master_ok is False

    with caplog.at_level(logging.ERROR):
        asyncio.run(main())
    lines = [r.getMessage() for r in caplog.records if "does not answer" in r.getMessage()]
    assert len(lines) == 1, lines  # logged once, not per retry
    assert uri in lines[0]


def test_master_restart_renews_registrations(
    ros1_available: None, tmp_path: Path, start_peer: Any, caplog: pytest.LogCaptureFixture
) -> None:
    core = Roscore(workdir=tmp_path / "core")
    core.start()

    async def main() -> None:
        async with Node("survivor", master_uri=core.uri, watch_period=0.2) as node:
            pub = await node.advertise("/survive", "std_msgs/String")
            await asyncio.to_thread(core.stop)
            await wait_until(lambda: node.master_ok is False)
            await asyncio.to_thread(core.start)
            await wait_until(lambda: node.master_ok is True)
            publishers, _, _ = await node.master.system_state()
            assert publishers["/survive"] == [node.name]
            listener = await asyncio.to_thread(
                start_peer, "listener.py", "/survive", "String", core=core
            )
            await pub.wait_for_subscribers(1, timeout=20)
            pub.publish(node.types.new("std_msgs/String", data="after restart"))
            assert await asyncio.to_thread(listener.expect, "got") == "got after restart"

    try:
        with caplog.at_level(logging.WARNING):
            asyncio.run(main())
    finally:
        core.close()
    assert "does not answer" in caplog.text
    assert "answers again" in caplog.text


def test_publisher_that_returns_is_reconnected(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        async with Node("patient", master_uri=roscore.uri) as node:
            got: list[str] = []
            sub = await node.subscribe("/comeback", "std_msgs/String", lambda m: got.append(m.data))
            talker = await asyncio.to_thread(start_peer, "talker.py", "/comeback", "String", "20")
            await wait_until(lambda: len(got) >= 3)
            await asyncio.to_thread(talker.stop)
            await wait_until(lambda: sub.num_connections == 0)
            got.clear()
            await asyncio.to_thread(start_peer, "talker.py", "/comeback", "String", "20")
            await wait_until(lambda: len(got) >= 3)
            assert got[0].startswith("hello")

    asyncio.run(main())
