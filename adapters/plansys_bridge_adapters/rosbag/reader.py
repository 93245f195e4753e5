"""Streaming reads of robot poses from ROS 1 and ROS 2 bags.

One reader serves ROS 1 bags (``.bag``) and ROS 2 bags (a rosbag2 directory, or a
bare ``.mcap`` / ``.db3`` file), through rosbags' ``AnyReader``. Messages are read one
at a time from the bag's chunks, so memory stays flat whatever the bag's size.

ROS 1 messages are converted to their ROS 2 types on the fly (CDR bytes of the
ROS 2 Humble definition: the ROS 1 header's ``seq`` disappears, the rest keeps its
wire layout), which is the bridging a ROS 1 robot needs when a ROS 2 planner drives
it. Every sample keeps those CDR bytes, so the pose can be written to a ROS 2 bag or
re-published without serialising it again.

Failures are :class:`~.errors.BagError` subclasses naming the bag, the topic and the
timestamp of the last message read correctly.
"""

from __future__ import annotations

import lzma
import math
import struct
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

from rosbags.convert.converter import is_same_wireformat
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.rosbag1 import ReaderError as Ros1ReaderError
from rosbags.rosbag2 import ReaderError as Ros2ReaderError
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, TypesysError, get_typestore

from .errors import BagCorruptError, BagError, BagTopicError, BagTypeError
from .ros1_pose import ros1_pose

try:  # rosbags decompresses mcap chunks with zstd (backport before Python 3.14)
    from compression.zstd import ZstdError  # type: ignore[import-not-found,unused-ignore]
except ImportError:  # pragma: no cover - depends on the Python version
    from backports.zstd import ZstdError  # type: ignore[import-not-found,no-redef,unused-ignore]

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.typesys.store import Typestore

ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
POSE_WITH_COVARIANCE_STAMPED = "geometry_msgs/msg/PoseWithCovarianceStamped"
POSE_TYPES = frozenset({ODOMETRY, POSE_STAMPED, POSE_WITH_COVARIANCE_STAMPED})
"""Message types a pose can be taken from."""

# What a damaged file raises from inside rosbags, its storage backends and the
# decompressors of bag chunks. Anything here, met while reading, means "corrupt".
_READ_ERRORS: tuple[type[BaseException], ...] = (
    AnyReaderError,
    Ros1ReaderError,
    Ros2ReaderError,
    SerdeError,
    TypesysError,
    struct.error,
    EOFError,
    OSError,
    ValueError,
    KeyError,
    IndexError,
    AssertionError,
    zlib.error,
    lzma.LZMAError,
    ZstdError,
    RuntimeError,  # lz4 frame errors
    # A damaged length field (mcap records carry a uint64 size) makes the reader ask
    # for more bytes than an index can hold (OverflowError) or memory can (MemoryError).
    OverflowError,
    MemoryError,
)


@cache
def ros2_typestore() -> Typestore:
    """The ROS 2 Humble type store every message is converted to (built once)."""
    return get_typestore(Stores.ROS2_HUMBLE)


def yaw_from_quaternion(qx: float, qy: float, qz: float, qw: float) -> float:
    """Heading (rotation about z) in radians, in (-pi, pi]."""
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


@dataclass(frozen=True, eq=False)
class PoseSample:
    """One pose read from a bag.

    ``bag_time_ns`` is the bag's record time (what replay timing follows);
    ``stamp`` is the message header stamp in seconds (the robot's clock then).
    ``wire`` holds the message as read: ROS 2 CDR bytes of type ``msgtype``, or with
    ``wire_ros1`` its ROS 1 serialisation; :attr:`cdr` gives the CDR bytes either way
    (a ROS 1 message is converted when they are first asked for, not while reading).
    """

    bag_time_ns: int
    stamp: float
    frame_id: str
    x: float
    y: float
    z: float
    qx: float
    qy: float
    qz: float
    qw: float
    msgtype: str
    wire: bytes
    wire_ros1: bool = False

    @property
    def cdr(self) -> bytes:
        """The message as ROS 2 CDR bytes (to write to a ROS 2 bag or re-publish)."""
        if not self.wire_ros1:
            return self.wire
        cached: bytes | None = self.__dict__.get("_cdr")
        if cached is None:
            cached = bytes(ros2_typestore().ros1_to_cdr(self.wire, self.msgtype))
            object.__setattr__(self, "_cdr", cached)
        return cached

    def __eq__(self, other: object) -> bool:
        """Same pose and the same message (CDR bytes), however each was read."""
        if not isinstance(other, PoseSample):
            return NotImplemented
        return self._key() == other._key() and self.cdr == other.cdr

    def __hash__(self) -> int:
        return hash(self._key())

    def _key(self) -> tuple[object, ...]:
        return (
            self.bag_time_ns,
            self.stamp,
            self.frame_id,
            self.x,
            self.y,
            self.z,
            self.qx,
            self.qy,
            self.qz,
            self.qw,
            self.msgtype,
        )

    @property
    def yaw(self) -> float:
        return yaw_from_quaternion(self.qx, self.qy, self.qz, self.qw)

    def message(self) -> Any:
        """The ROS 2 message object (decoded from ``cdr`` on demand)."""
        return ros2_typestore().deserialize_cdr(self.cdr, self.msgtype)


@dataclass(frozen=True)
class RawMessage:
    """One message as ROS 2 CDR bytes, with its bag time and type."""

    topic: str
    msgtype: str
    bag_time_ns: int
    cdr: bytes


def pose_from_message(
    msg: Any, msgtype: str, bag_time_ns: int, wire: bytes, wire_ros1: bool = False
) -> PoseSample:
    """Extract the pose of an Odometry / PoseStamped / PoseWithCovarianceStamped."""
    pose = msg.pose if msgtype == POSE_STAMPED else msg.pose.pose
    stamp = msg.header.stamp
    p, q = pose.position, pose.orientation
    # Filled in directly rather than through the frozen dataclass's __init__ (one
    # object.__setattr__ per field): a bag is read at tens of thousands of poses per
    # second, and this was a good part of the cost of each.
    sample = object.__new__(PoseSample)
    sample.__dict__.update(
        bag_time_ns=bag_time_ns,
        stamp=stamp.sec + stamp.nanosec * 1e-9,
        frame_id=msg.header.frame_id,
        x=float(p.x),
        y=float(p.y),
        z=float(p.z),
        qx=float(q.x),
        qy=float(q.y),
        qz=float(q.z),
        qw=float(q.w),
        msgtype=msgtype,
        wire=wire,
        wire_ros1=wire_ros1,
    )
    return sample


class BagReader:
    """An open ROS 1 or ROS 2 bag; a context manager.

    ``messages()`` and ``poses()`` are generators that read the bag lazily; they may
    be called several times (each call reads the bag again from the window start).
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._reader: AnyReader | None = None

    # -- lifecycle ---------------------------------------------------------------
    def open(self) -> BagReader:
        if not self.path.exists():
            raise BagError("bag not found", self.path)
        if self.path.is_file() and self.path.suffix not in {".bag", ".mcap", ".db3"}:
            raise BagError(
                f"unknown bag format {self.path.suffix!r} (expected .bag, .mcap, .db3 "
                "or a rosbag2 directory)",
                self.path,
            )
        try:
            reader = AnyReader([self.path], default_typestore=ros2_typestore())
            reader.open()
        except _READ_ERRORS as exc:
            raise BagCorruptError(
                f"cannot open bag (truncated or damaged?): {exc}", self.path
            ) from exc
        self._reader = reader
        return self

    def close(self) -> None:
        reader, self._reader = self._reader, None
        if reader is not None:
            try:
                reader.close()
            except _READ_ERRORS as exc:
                raise BagCorruptError(f"error while closing bag: {exc}", self.path) from exc

    def __enter__(self) -> BagReader:
        return self.open()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    @property
    def reader(self) -> AnyReader:
        if self._reader is None:
            raise BagError("bag is not open", self.path)
        return self._reader

    # -- metadata ----------------------------------------------------------------
    @property
    def is_ros1(self) -> bool:
        return not self.reader.is2

    @property
    def start_ns(self) -> int:
        return int(self.reader.start_time)

    @property
    def end_ns(self) -> int:
        return int(self.reader.end_time)

    @property
    def topics(self) -> dict[str, str]:
        """Topic name -> message type (ROS 2 spelling, e.g. ``nav_msgs/msg/Odometry``)."""
        return {c.topic: c.msgtype for c in self.reader.connections}

    def message_count(self, topic: str) -> int:
        return sum(c.msgcount for c in self._connections(topic))

    def _connections(self, topic: str) -> list[Connection]:
        conns = [c for c in self.reader.connections if c.topic == topic]
        if not conns:
            known = ", ".join(sorted(self.topics)) or "none"
            raise BagTopicError(f"topic not in bag (topics: {known})", self.path, topic)
        return conns

    def msgtype(self, topic: str) -> str:
        types = {c.msgtype for c in self._connections(topic)}
        if len(types) != 1:
            raise BagTypeError(f"topic has several types: {sorted(types)}", self.path, topic)
        return types.pop()

    # -- reading -----------------------------------------------------------------
    def messages(
        self,
        topics: str | Sequence[str],
        start_ns: int | None = None,
        stop_ns: int | None = None,
    ) -> Iterator[RawMessage]:
        """Messages of one or several topics in ``[start_ns, stop_ns)``, in time order,
        as ROS 2 CDR bytes (ROS 1 messages converted)."""
        names = [topics] if isinstance(topics, str) else list(topics)
        store = ros2_typestore()
        conns: list[Connection] = []
        types: dict[str, str] = {}
        for topic in names:
            types[topic] = self.ros2_msgtype(topic)
            conns.extend(self._connections(topic))
        ros1 = self.is_ros1
        for conn, timestamp, raw in self._raw(names, conns, start_ns, stop_ns):
            msgtype = types[conn.topic]
            try:
                cdr = bytes(store.ros1_to_cdr(raw, msgtype)) if ros1 else bytes(raw)
            except _READ_ERRORS as exc:
                raise self._undecodable(msgtype, conn.topic, timestamp, exc) from exc
            yield RawMessage(conn.topic, msgtype, timestamp, cdr)

    def _undecodable(
        self, msgtype: str, topic: str, timestamp: int, exc: BaseException
    ) -> BagCorruptError:
        return BagCorruptError(
            f"message cannot be decoded as {msgtype}: {exc}", self.path, topic, timestamp
        )

    def _raw(
        self,
        names: Sequence[str],
        conns: list[Connection],
        start_ns: int | None,
        stop_ns: int | None,
    ) -> Iterator[tuple[Connection, int, bytes]]:
        """The bag's messages as stored; a damaged bag is a BagCorruptError naming the
        last good message."""
        where = names[0] if len(names) == 1 else ", ".join(names)
        last: int | None = None
        it = self.reader.messages(conns, start=start_ns, stop=stop_ns)
        while True:
            try:
                conn, timestamp, raw = next(it)
            except StopIteration:
                return
            except _READ_ERRORS as exc:
                raise BagCorruptError(
                    f"bag truncated or damaged after the last good message: {exc}",
                    self.path,
                    where,
                    last,
                ) from exc
            last = timestamp
            yield conn, timestamp, raw

    def ros2_msgtype(self, topic: str) -> str:
        """The topic's ROS 2 type; BagTypeError if its messages cannot be given as one.

        The type must be known to ROS 2 Humble, and a ROS 1 definition must have the
        ROS 2 type's layout (bar the header's ``seq``). Nothing is read.
        """
        msgtype = self.msgtype(topic)
        if msgtype not in ros2_typestore().fielddefs:
            raise BagTypeError(
                f"message type {msgtype} is unknown to ROS 2 Humble", self.path, topic
            )
        if self.is_ros1:
            self._check_convertible(topic, msgtype)
        return msgtype

    def _check_convertible(self, topic: str, msgtype: str) -> None:
        try:
            same = is_same_wireformat(self.reader.typestore, ros2_typestore(), msgtype, msgtype)
        except KeyError as exc:
            same = False
            detail = f" (no definition of {exc})"
        else:
            detail = ""
        if not same:
            raise BagTypeError(
                f"the bag's ROS 1 definition of {msgtype} differs from ROS 2 Humble's{detail}; "
                "it cannot be converted",
                self.path,
                topic,
            )

    def poses(
        self, topic: str, start_ns: int | None = None, stop_ns: int | None = None
    ) -> Iterator[PoseSample]:
        """Poses of ``topic`` (Odometry, PoseStamped or PoseWithCovarianceStamped)."""
        msgtype = self.msgtype(topic)
        if msgtype not in POSE_TYPES:
            raise BagTypeError(
                f"type {msgtype} carries no pose (expected one of {sorted(POSE_TYPES)})",
                self.path,
                topic,
            )
        self.ros2_msgtype(topic)  # convertible to ROS 2, or BagTypeError now
        conns = self._connections(topic)
        if self.is_ros1:
            yield from self._ros1_poses(topic, msgtype, conns, start_ns, stop_ns)
            return
        store = ros2_typestore()
        for _conn, timestamp, raw in self._raw([topic], conns, start_ns, stop_ns):
            try:
                msg = store.deserialize_cdr(raw, msgtype)
            except _READ_ERRORS as exc:
                raise self._undecodable(msgtype, topic, timestamp, exc) from exc
            yield pose_from_message(msg, msgtype, timestamp, bytes(raw))

    def _ros1_poses(
        self,
        topic: str,
        msgtype: str,
        conns: list[Connection],
        start_ns: int | None,
        stop_ns: int | None,
    ) -> Iterator[PoseSample]:
        """ROS 1 poses read from the front of each message (:mod:`.ros1_pose`); the
        CDR bytes are made only if someone asks for them."""
        odometry = msgtype == ODOMETRY
        for _conn, timestamp, raw in self._raw([topic], conns, start_ns, stop_ns):
            try:
                stamp, frame_id, (x, y, z, qx, qy, qz, qw) = ros1_pose(raw, odometry)
            except (struct.error, UnicodeDecodeError) as exc:
                raise self._undecodable(msgtype, topic, timestamp, exc) from exc
            sample = object.__new__(PoseSample)  # see pose_from_message
            sample.__dict__.update(
                bag_time_ns=timestamp,
                stamp=stamp,
                frame_id=frame_id,
                x=x,
                y=y,
                z=z,
                qx=qx,
                qy=qy,
                qz=qz,
                qw=qw,
                msgtype=msgtype,
                wire=bytes(raw),
                wire_ros1=True,
            )
            yield sample


def read_poses(
    path: str | Path, topic: str, start_ns: int | None = None, stop_ns: int | None = None
) -> Iterator[PoseSample]:
    """Open ``path``, stream the poses of ``topic``, close the bag when done."""
    with BagReader(path) as bag:
        yield from bag.poses(topic, start_ns, stop_ns)
