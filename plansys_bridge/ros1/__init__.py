"""A ROS 1 client in plain Python (no rospy): master, slave API, TCPROS, actionlib.

``Node`` registers publishers and subscribers with a ROS master and talks TCPROS to
rospy and roscpp peers; ``ActionClient`` drives an actionlib server such as
move_base. Message types come from rosbags' ROS 1 typestore (``Ros1Types``).
"""

from __future__ import annotations

from plansys_bridge.ros1.errors import MasterError, MasterUnreachable, ProtocolError, Ros1Error
from plansys_bridge.ros1.node import DEFAULT_MASTER_URI, Node, resolve_topic
from plansys_bridge.ros1.topics import Publisher, Subscriber
from plansys_bridge.ros1.types import Ros1Types, ros1_name, store_name

__all__ = [
    "DEFAULT_MASTER_URI",
    "MasterError",
    "MasterUnreachable",
    "Node",
    "ProtocolError",
    "Publisher",
    "Ros1Error",
    "Ros1Types",
    "Subscriber",
    "resolve_topic",
    "ros1_name",
    "store_name",
]
