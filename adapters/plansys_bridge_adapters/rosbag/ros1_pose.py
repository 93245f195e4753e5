"""The pose of a ROS 1 Odometry / PoseStamped / PoseWithCovarianceStamped, read
straight from its serialisation.

A pose is a few fields at the front of these messages (header, for Odometry the
child frame, then position and orientation); decoding the whole message, covariance
matrices and twist included, was most of the cost of reading a bag. The layout is
ROS 1's (little-endian, a string is a uint32 length and its bytes) and the reader
only uses this after checking that the bag's definition of the type is the standard
one (the same wire format as ROS 2 Humble's).
"""

from __future__ import annotations

import struct

__all__ = ["Ros1Pose", "ros1_pose"]

_HEADER = struct.Struct("<4xIII")
"""seq (skipped), stamp sec, stamp nsec, frame_id length."""
_LENGTH = struct.Struct("<I")
_POSE = struct.Struct("<7d")

Ros1Pose = tuple[float, str, tuple[float, float, float, float, float, float, float]]
"""(stamp in seconds, frame_id, (x, y, z, qx, qy, qz, qw))."""


def ros1_pose(raw: bytes | memoryview, odometry: bool) -> Ros1Pose:
    """Stamp, frame and pose of one message; ``odometry``: the message is an Odometry
    (a child frame id sits between header and pose). ``struct.error`` or
    ``UnicodeDecodeError`` when the bytes are too short or not text where text is."""
    sec, nsec, length = _HEADER.unpack_from(raw, 0)
    offset = _HEADER.size
    frame_id = bytes(raw[offset : offset + length]).decode()
    if len(frame_id.encode()) != length:
        raise struct.error("frame_id runs past the end of the message")
    offset += length
    if odometry:
        (child,) = _LENGTH.unpack_from(raw, offset)
        offset += _LENGTH.size + child
    pose = _POSE.unpack_from(raw, offset)
    return sec + nsec * 1e-9, frame_id, pose
