"""A ROS 1 topic field as a sensing source, read with the project's ROS 1 client from
a rospy talker (Debian's rospy, run with /usr/bin/python3) through Debian's roscore."""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sensing"))

from ros_rules import engine, knowledge, wait_until

from plansys_bridge.ros1.roscore import Roscore


def test_odometry_from_rospy_sets_a_predicate(roscore: Roscore, start_peer: Any) -> None:
    k = knowledge()
    rule = {
        "from": "ros1",
        "topic": "/r2d2/odom",
        "type": "nav_msgs/msg/Odometry",
        "master_uri": roscore.uri,
        "when": "pose.pose.position.x >= 5",
        "predicate": "(battery_low r2d2)",
    }
    value = {**rule, "field": "pose.pose.position.x", "function": "(battery_level r2d2)"}
    del value["when"], value["predicate"]

    async def main() -> None:
        sensing = engine(k, rule, value)
        sensing.start({})
        try:
            start_peer("talker.py", "/r2d2/odom", "Odometry", "20")
            await wait_until(lambda: k.exist_predicate("(battery_low r2d2)"))
            level = k.get_function("(battery_level r2d2)")
            assert level is not None and level >= 5
        finally:
            sensing.stop()
            await asyncio.sleep(0.2)  # the node unregisters

    asyncio.run(main())
