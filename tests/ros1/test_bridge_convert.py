"""ROS 1 <-> ROS 2 conversion from the two typestores (no ROS needed)."""

from __future__ import annotations

import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from plansys_bridge.bridge.convert import Converter
from plansys_bridge.interfaces.typestore import ros2_typestore
from plansys_bridge.ros1.errors import Ros1Error
from plansys_bridge.ros1.types import Ros1Types


def test_odometry_round_trip_drops_and_numbers_header_seq() -> None:
    ros1 = Ros1Types.default()
    conv = Converter("nav_msgs/msg/Odometry", ros1, ros2_typestore())
    msg = ros1.new("nav_msgs/msg/Odometry", child_frame_id="base_link")
    msg.header.seq = 41
    msg.header.frame_id = "odom"
    msg.header.stamp.sec, msg.header.stamp.nanosec = 1_700_000_000, 5
    msg.pose.covariance[0] = 0.25
    two = conv.to_ros2(msg)
    assert not hasattr(two.header, "seq")
    assert (two.header.frame_id, two.header.stamp.sec, two.header.stamp.nanosec) == (
        "odom",
        1_700_000_000,
        5,
    )
    assert two.pose.covariance[0] == 0.25 and two.child_frame_id == "base_link"
    back = conv.to_ros1(two, seq=7)
    assert back.header.seq == 7
    wire = ros1.serialize(back, "nav_msgs/msg/Odometry")
    assert ros1.deserialize(wire, "nav_msgs/Odometry").pose.covariance[0] == 0.25


def test_tf_message_lists_convert_element_by_element() -> None:
    ros1 = Ros1Types.default()
    conv = Converter("tf2_msgs/msg/TFMessage", ros1, ros2_typestore())
    tf = ros1.new("geometry_msgs/msg/TransformStamped", child_frame_id="base_footprint")
    tf.header.seq = 3
    two = conv.to_ros2(ros1.new("tf2_msgs/msg/TFMessage", transforms=[tf, tf]))
    assert [t.child_frame_id for t in two.transforms] == ["base_footprint"] * 2


def test_types_that_disagree_are_refused_up_front() -> None:
    ros1 = Ros1Types()
    ros1.register_texts({"demo_msgs/msg/Level": "float32 value\n"})
    ros2 = ros2_typestore()
    with pytest.raises(Ros1Error, match="unknown ROS 2 message type 'demo_msgs/msg/Level'"):
        Converter("demo_msgs/msg/Level", ros1, ros2)
    other = get_typestore(Stores.EMPTY)
    other.register(get_types_from_msg("float64 value\n", "demo_msgs/msg/Level"))
    with pytest.raises(Ros1Error, match=r"Level\.value is float32 in ROS 1 but float64 in ROS 2"):
        Converter("demo_msgs/msg/Level", ros1, other)
