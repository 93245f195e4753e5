"""ROS 1 types and TCPROS framing: md5sums equal rospy's, headers round-trip or fail cleanly."""

from __future__ import annotations

import asyncio
import json
import subprocess

import pytest

from plansys_bridge.ros1.errors import ProtocolError, Ros1Error
from plansys_bridge.ros1.roscore import SYSTEM_PYTHON
from plansys_bridge.ros1.tcpros import decode_header, encode_header, frame, read_frame
from plansys_bridge.ros1.types import Ros1Types, action_texts, ros1_name, store_name

CHECKED = [
    "std_msgs/String",
    "nav_msgs/Odometry",
    "geometry_msgs/Twist",
    "geometry_msgs/PoseStamped",
    "actionlib_msgs/GoalID",
    "actionlib_msgs/GoalStatusArray",
    "move_base_msgs/MoveBaseGoal",
    "move_base_msgs/MoveBaseFeedback",
    "move_base_msgs/MoveBaseResult",
    "move_base_msgs/MoveBaseActionGoal",
    "move_base_msgs/MoveBaseActionFeedback",
    "move_base_msgs/MoveBaseActionResult",
    "move_base_msgs/RecoveryStatus",
]


def test_md5sums_equal_rospy(ros1_available: None) -> None:
    code = (
        "import importlib, json, sys\n"
        "out = {}\n"
        "for name in sys.argv[1:]:\n"
        "    pkg, typ = name.split('/')\n"
        "    out[name] = getattr(importlib.import_module(pkg + '.msg'), typ)._md5sum\n"
        "print(json.dumps(out))\n"
    )
    result = subprocess.run(
        [SYSTEM_PYTHON, "-c", code, *CHECKED], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    theirs = json.loads(result.stdout)
    types = Ros1Types.default()
    assert {name: types.md5sum(name) for name in CHECKED} == theirs


@pytest.mark.parametrize(
    ("name", "md5"),
    [
        ("tf2_msgs/TFMessage", "94810edda583a504dfda3829e70d7eec"),
        ("sensor_msgs/LaserScan", "90c7ef2dc6895d81024acba2ac42f369"),
        ("sensor_msgs/Imu", "6a62c6daae103f4ff57a132d6f95cec2"),
    ],
)
def test_tiago_types_md5_are_the_noetic_ones(name: str, md5: str) -> None:
    # Not packaged for Debian's rospy here: the md5sums are the ones `rosbag info`
    # prints for these types in ROS Noetic bags.
    assert Ros1Types.default().md5sum(name) == md5


def test_names_and_custom_types() -> None:
    assert store_name("std_msgs/String") == "std_msgs/msg/String"
    assert ros1_name("std_msgs/msg/String") == "std_msgs/String"
    with pytest.raises(Ros1Error, match="not a message type name"):
        store_name("String")
    types = Ros1Types()
    types.register_texts({"my_msgs/Ping": "uint32 n\nstring who\n"})
    msg = types.new("my_msgs/Ping", n=7, who="me")
    assert types.deserialize(types.serialize(msg, "my_msgs/Ping"), "my_msgs/msg/Ping").n == 7
    with pytest.raises(Ros1Error, match="unknown ROS 1 message type 'my_msgs/Pong'"):
        types.md5sum("my_msgs/Pong")
    with pytest.raises(Ros1Error, match="cannot parse"):
        types.register_texts({"my_msgs/Bad": "uint32[ n\n"})
    with pytest.raises(Ros1Error, match="cannot deserialise a std_msgs/String"):
        types.deserialize(b"\xff\xff\xff\x7f", "std_msgs/String")


def test_action_texts_need_three_parts() -> None:
    assert set(action_texts("p", "A", "int8 a\n---\n---\n")) >= {"AActionGoal", "AFeedback"}
    with pytest.raises(Ros1Error, match=r"p/A\.action"):
        action_texts("p", "A", "int8 a\n")


def test_header_round_trip_and_malformed() -> None:
    fields = {"callerid": "/n", "topic": "/t", "message_definition": "string data\n"}
    raw = encode_header(fields)
    assert decode_header(raw[4:]) == fields
    with pytest.raises(ProtocolError, match="not key=value"):
        decode_header(b"\x03\x00\x00\x00abc")
    with pytest.raises(ProtocolError, match="overruns"):
        decode_header(b"\xff\x00\x00\x00abc")
    with pytest.raises(ProtocolError, match="cut short"):
        decode_header(b"\x01\x00")


def test_frames_cut_short_or_too_big() -> None:
    async def read(data: bytes) -> bytes:
        reader = asyncio.StreamReader()
        reader.feed_data(data)
        reader.feed_eof()
        return await read_frame(reader)

    assert asyncio.run(read(frame(b"abc"))) == b"abc"
    with pytest.raises(ProtocolError, match="cut short: 2 of 5 bytes"):
        asyncio.run(read(frame(b"abcde")[:6]))
    with pytest.raises(ProtocolError, match="exceeds the limit"):
        asyncio.run(read(b"\xff\xff\xff\xff"))
    with pytest.raises(EOFError):
        asyncio.run(read(b""))
