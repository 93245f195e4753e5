"""The ROS 1 <-> ROS 2 bridge between rospy peers and a Cyclone DDS peer.

The ROS 2 peer is a Cyclone DDS participant whose types are written here from the
upstream ROS 2 .msg texts (std_msgs/msg/String, nav_msgs/msg/Odometry and what it
contains, ros2/common_interfaces humble), with ROS 2's DDS names; it shares no code
with the bridge's generated types. This module has no ``from __future__ import
annotations``: cyclonedds evaluates the field annotations.
"""

import asyncio
import time
from dataclasses import dataclass, field
from typing import Any

import pytest

pytest.importorskip("cyclonedds")

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float64
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from ros2_upstream import Header_, Pose_

from plansys_bridge.bridge.bridge import Bridge
from plansys_bridge.bridge.config import parse_bridge_config
from plansys_bridge.hub.dds_config import loopback_config
from plansys_bridge.hub.dds_participant import SharedDomain
from plansys_bridge.ros1.roscore import Roscore

DOMAIN = 77


# std_msgs/msg/String: "string data"
@dataclass
class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str = ""


# geometry_msgs/msg/PoseWithCovariance: "Pose pose / float64[36] covariance"
@dataclass
class PoseWithCovariance_(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose_ = field(default_factory=Pose_)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class Vector3_(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Twist_(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3_ = field(default_factory=Vector3_)
    angular: Vector3_ = field(default_factory=Vector3_)


@dataclass
class TwistWithCovariance_(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist_ = field(default_factory=Twist_)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


# nav_msgs/msg/Odometry: "std_msgs/Header header / string child_frame_id /
# geometry_msgs/PoseWithCovariance pose / geometry_msgs/TwistWithCovariance twist"
@dataclass
class Odometry_(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header_ = field(default_factory=Header_)
    child_frame_id: str = ""
    pose: PoseWithCovariance_ = field(default_factory=PoseWithCovariance_)
    twist: TwistWithCovariance_ = field(default_factory=TwistWithCovariance_)


QOS = Qos(
    Policy.Reliability.Reliable(duration(seconds=1)),
    Policy.History.KeepLast(50),
    Policy.DataRepresentation(use_cdrv0_representation=True),
)


@pytest.fixture(autouse=True)
def _loopback_domain() -> Any:
    """The test's DDS peer joins the domain with the loopback config the bridge uses."""
    SharedDomain.acquire(DOMAIN, loopback_config(DOMAIN))
    yield
    SharedDomain.release(DOMAIN)


def config(core: Roscore, topics: list[dict[str, Any]]) -> Any:
    return parse_bridge_config(
        {"ros1": {"master_uri": core.uri}, "ros2": {"domain_id": DOMAIN}, "topics": topics}
    )


async def take_until(reader: DataReader, count: int, timeout: float = 30.0) -> list[Any]:
    got: list[Any] = []
    deadline = time.monotonic() + timeout
    while len(got) < count and time.monotonic() < deadline:
        got.extend(reader.take(100))
        await asyncio.sleep(0.05)
    return got


def test_ros1_talker_reaches_a_ros2_reader(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        cfg = config(
            roscore,
            [
                {"topic": "/chatter", "type": "std_msgs/msg/String", "from": "ros1"},
                {
                    "topic": "/mobile_base_controller/odom",
                    "to": "/odom",
                    "type": "nav_msgs/msg/Odometry",
                    "from": "ros1",
                    "rate": 5,
                },
            ],
        )
        async with Bridge(cfg) as bridge:
            participant = DomainParticipant(DOMAIN)
            chatter = DataReader(participant, Topic(participant, "rt/chatter", String_), QOS)
            odom = DataReader(participant, Topic(participant, "rt/odom", Odometry_), QOS)
            await asyncio.to_thread(start_peer, "talker.py", "/chatter", "String", "20")
            await asyncio.to_thread(
                start_peer, "talker.py", "/mobile_base_controller/odom", "Odometry", "50"
            )
            strings = await take_until(chatter, 5)
            assert len(strings) >= 5
            assert all(s.data.startswith("hello ") for s in strings)
            odoms = await take_until(odom, 3)
            assert len(odoms) >= 3
            assert odoms[0].header.frame_id == "odom" and odoms[0].child_frame_id == "base_link"
            assert odoms[-1].pose.pose.position.x > odoms[0].pose.pose.position.x
            assert odoms[0].pose.pose.orientation.w == 1.0
            assert odoms[0].header.stamp.sec > 1_600_000_000
            odom_stats = next(s for s in bridge.stats if s.route.target == "/odom")
            assert odom_stats.skipped > 0  # 50 Hz in, at most 5 Hz out

    asyncio.run(main())


def test_ros2_writer_reaches_a_rospy_listener(roscore: Roscore, start_peer: Any) -> None:
    async def main() -> None:
        cfg = config(roscore, [{"topic": "/cmd", "type": "std_msgs/msg/String", "from": "ros2"}])
        async with Bridge(cfg):
            listener = await asyncio.to_thread(start_peer, "listener.py", "/cmd", "String")
            participant = DomainParticipant(DOMAIN)
            writer = DataWriter(participant, Topic(participant, "rt/cmd", String_), QOS)
            line = ""
            for i in range(100):
                writer.write(String_(data=f"go {i}"))
                try:
                    line = await asyncio.to_thread(listener.expect, "got", 0.2)
                    break
                except AssertionError:
                    continue
            assert line.startswith("got go ")

    asyncio.run(main())


@pytest.mark.parametrize(
    ("entry", "key", "text"),
    [
        ({"topic": "/a", "type": "std_msgs/String", "from": "ros1"}, "topics[0].type", "ROS 2"),
        ({"topic": "/a", "type": "std_msgs/msg/String", "from": "ros3"}, "topics[0].from", "ros1"),
        ({"topic": "/a", "type": "std_msgs/msg/String"}, "topics[0]", "missing 'from'"),
        (
            {"topic": "/a", "type": "std_msgs/msg/String", "from": "ros1", "rate": 0},
            "topics[0].rate",
            "> 0",
        ),
        (
            {"topic": "/a", "type": "std_msgs/msg/String", "from": "ros1", "qos": {"depth": 0}},
            "topics[0].qos.depth",
            ">= 1",
        ),
        ({"topic": "/a", "typ": "x"}, "topics[0].typ", "unknown key"),
    ],
)
def test_bad_bridge_entries_name_their_key(entry: dict[str, Any], key: str, text: str) -> None:
    from plansys_bridge.errors import ConfigError

    with pytest.raises(ConfigError) as info:
        parse_bridge_config(
            {"ros1": {}, "ros2": {"domain_id": 1}, "topics": [entry]}, source="b.yaml"
        )
    message = str(info.value)
    assert message.startswith(f"b.yaml:{key}:") and text in message, message


def test_a_topic_bridged_both_ways_is_refused() -> None:
    from plansys_bridge.errors import ConfigError

    topics = [
        {"topic": "/a", "to": "/b", "type": "std_msgs/msg/String", "from": "ros1"},
        {"topic": "/b", "to": "/a", "type": "std_msgs/msg/String", "from": "ros2"},
    ]
    loop = r"topics\[0\]: /b would go round in a loop: topics\[1\] bridges it back"
    with pytest.raises(ConfigError, match=loop):
        parse_bridge_config({"ros2": {"domain_id": 1}, "topics": topics}, source="b.yaml")
