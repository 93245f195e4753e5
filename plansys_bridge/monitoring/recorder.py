"""Record a mission run to a ROS 2 bag (MCAP storage).

:class:`MissionRecorder` subscribes to every hub topic and writes each message, as
its ``plansys2_msgs`` type, to a rosbag2 directory (``metadata.yaml`` plus one
``.mcap`` file). Adapters add their telemetry through :meth:`MissionRecorder.record_pose`
or :meth:`MissionRecorder.record`; the planner's output goes in with
:meth:`MissionRecorder.record_plan`. The bag opens with rosbags, ``ros2 bag``, and any
MCAP reader (the message definitions are embedded).

Bag topics are the hub topic names with a leading ``/`` (``/actions_hub``); the
``rt/`` prefix is a DDS wire detail and does not appear in bags. Log times are the
hub clock's mission time, so a virtual-clock run records the mission timeline, not
the few wall seconds it took.

Writes are serialised by a lock: adapters may record from their own threads.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, Protocol

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.hub import messages as hm
from plansys_bridge.interfaces.convert import Encoder, message_encoder

from . import msgs
from .rosbags_api import SerdeError, StoragePlugin, Writer, WriterError, np

if TYPE_CHECKING:
    from rosbags.interfaces import Connection

log = logging.getLogger(__name__)


_PLAIN: tuple[tuple[type, str], ...] = (
    (hm.ActionExecutionInfo, msgs.ACTION_EXECUTION_INFO),
    (hm.ActionPerformerStatus, msgs.ACTION_PERFORMER_STATUS),
    (hm.Plan, msgs.PLAN),
    (hm.Knowledge, msgs.KNOWLEDGE),
)
"""Hub messages recorded as one ROS message of the same fields."""


class RecorderError(PlansysBridgeError):
    """The mission bag could not be created or written."""


class _Subscription(Protocol):
    def close(self) -> None: ...


class _Clock(Protocol):
    def now(self) -> float: ...


class _Hub(Protocol):
    """What the recorder needs from :class:`plansys_bridge.hub.transport.Hub`."""

    @property
    def clock(self) -> Any: ...

    def subscribe(self, topic: str, callback: Callable[[Any], None]) -> Any: ...


def bag_topic(hub_topic: str) -> str:
    """Hub topic name -> bag topic name (``actions_hub`` -> ``/actions_hub``)."""
    return hub_topic if hub_topic.startswith("/") else f"/{hub_topic}"


BRIDGE_PREFIX = "/plansys_bridge"
"""Bag topics holding the project's extra fields live under this namespace."""

PLAN_TOPIC = "/plan"
"""Where :meth:`MissionRecorder.record_plan` writes plans computed by the planner."""


def seconds_to_ns(seconds: float) -> int:
    return max(0, round(seconds * 1e9))


class MissionRecorder:
    """Writes hub traffic and telemetry of one mission run to a ROS 2 MCAP bag.

    ``path`` is the rosbag2 directory to create (it must not exist). Call
    :meth:`start` (or use ``with``) to subscribe, :meth:`close` to unsubscribe and
    finish the bag; an unfinished MCAP file has no summary and cannot be read.
    """

    HUB_TOPICS: tuple[str, ...] = (
        hm.Topics.ACTIONS_HUB,
        hm.Topics.PERFORMERS_STATUS,
        hm.Topics.ACTION_EXECUTION_INFO,
        hm.Topics.EXECUTING_PLAN,
        hm.Topics.KNOWLEDGE,
        hm.Topics.DOT_GRAPH,
    )

    def __init__(
        self,
        hub: _Hub,
        path: str | Path,
        *,
        topics: Iterable[str] | None = None,
        clock: _Clock | None = None,
    ) -> None:
        self.hub = hub
        self.path = Path(path)
        self.clock: _Clock = clock if clock is not None else hub.clock
        self.hub_topics = tuple(topics) if topics is not None else self.HUB_TOPICS
        self.store = msgs.hub_typestore()
        self._encoders: dict[str, Encoder] = {}
        self.counts: dict[str, int] = {}
        self.dropped = 0
        self._lock = threading.Lock()
        self._writer: Writer | None = None
        self._connections: dict[tuple[str, str], Connection] = {}
        self._subscriptions: list[_Subscription] = []

    # -- lifecycle ---------------------------------------------------------------
    def start(self) -> MissionRecorder:
        if self._writer is not None:
            raise RecorderError(f"{self.path}: recorder already started")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            writer = Writer(
                self.path, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP
            )
            writer.open()
        except (WriterError, OSError) as exc:
            raise RecorderError(f"{self.path}: cannot create mission bag: {exc}") from exc
        self._writer = writer
        for topic in self.hub_topics:
            self._subscriptions.append(self.hub.subscribe(topic, self._callback(topic)))
        return self

    def close(self) -> None:
        """Unsubscribe and finish the bag (idempotent)."""
        for sub in self._subscriptions:
            sub.close()
        self._subscriptions.clear()
        with self._lock:
            writer, self._writer = self._writer, None
            if writer is not None:
                try:
                    writer.close()
                except (WriterError, OSError) as exc:
                    raise RecorderError(f"{self.path}: cannot finish mission bag: {exc}") from exc

    def __enter__(self) -> MissionRecorder:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    @property
    def recording(self) -> bool:
        return self._writer is not None

    # -- adapters' API -------------------------------------------------------------
    def record(self, topic: str, msgtype: str, msg: object, stamp: float | None = None) -> None:
        """Write one ROS 2 message object (of a type known to the recorder's store).

        ``stamp`` is the log time in mission seconds (default: the clock's now).
        Build messages with ``recorder.store.types[msgtype](...)``.
        """
        try:
            data = self.store.serialize_cdr(msg, msgtype)
        except (SerdeError, KeyError, AttributeError, TypeError) as exc:
            raise RecorderError(
                f"{self.path} topic {topic}: cannot serialise {msgtype}: {exc}"
            ) from exc
        self.record_cdr(topic, msgtype, bytes(data), stamp)

    def record_cdr(self, topic: str, msgtype: str, data: bytes, stamp: float | None = None) -> None:
        """Write one message already serialised as ROS 2 CDR (e.g. read from a bag)."""
        if msgtype not in self.store.fielddefs:
            raise RecorderError(f"{self.path} topic {topic}: unknown message type {msgtype}")
        when = self.clock.now() if stamp is None else stamp
        with self._lock:
            writer = self._writer
            if writer is None:
                raise RecorderError(f"{self.path}: recorder is not recording")
            key = (topic, msgtype)
            conn = self._connections.get(key)
            try:
                if conn is None:
                    conn = writer.add_connection(topic, msgtype, typestore=self.store)
                    self._connections[key] = conn
                writer.write(conn, seconds_to_ns(when), data)
            except (WriterError, OSError) as exc:
                raise RecorderError(f"{self.path} topic {topic}: write failed: {exc}") from exc
            self.counts[topic] = self.counts.get(topic, 0) + 1

    def record_pose(
        self,
        topic: str,
        stamp: float,
        x: float,
        y: float,
        z: float = 0.0,
        yaw: float = 0.0,
        *,
        frame_id: str = "map",
    ) -> None:
        """Write a ``geometry_msgs/msg/PoseStamped`` (e.g. a vehicle's position)."""
        t = self.store.types
        half = yaw / 2.0
        msg = t["geometry_msgs/msg/PoseStamped"](
            header=self.header(stamp, frame_id),
            pose=t["geometry_msgs/msg/Pose"](
                position=t["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=float(z)),
                orientation=t["geometry_msgs/msg/Quaternion"](
                    x=0.0, y=0.0, z=math.sin(half), w=math.cos(half)
                ),
            ),
        )
        self.record(topic, "geometry_msgs/msg/PoseStamped", msg, stamp)

    def record_navsatfix(
        self,
        topic: str,
        stamp: float,
        latitude: float,
        longitude: float,
        altitude: float,
        *,
        frame_id: str = "gps",
    ) -> None:
        """Write a ``sensor_msgs/msg/NavSatFix`` (e.g. a MAVLink GLOBAL_POSITION_INT)."""
        t = self.store.types
        fix: Any = t["sensor_msgs/msg/NavSatFix"]
        status_t: Any = t["sensor_msgs/msg/NavSatStatus"]
        msg = fix(
            header=self.header(stamp, frame_id),
            status=status_t(status=status_t.STATUS_FIX, service=status_t.SERVICE_GPS),
            latitude=float(latitude),
            longitude=float(longitude),
            altitude=float(altitude),
            position_covariance=_zeros9(),
            position_covariance_type=fix.COVARIANCE_TYPE_UNKNOWN,
        )
        self.record(topic, "sensor_msgs/msg/NavSatFix", msg, stamp)

    def record_plan(
        self, plan: hm.Plan, stamp: float | None = None, topic: str = PLAN_TOPIC
    ) -> None:
        """Write a plan (as ``plansys2_msgs/msg/Plan``), e.g. the planner's answer."""
        self.record(topic, msgs.PLAN, self._plan(plan), stamp)

    # -- conversions -----------------------------------------------------------------
    @staticmethod
    def _split(seconds: float, what: str = "stamp") -> tuple[int, int]:
        sec = math.floor(seconds)
        return int(sec), min(999_999_999, round((seconds - sec) * 1e9))

    def time(self, seconds: float) -> Any:
        sec, nanosec = self._split(seconds)
        return self.store.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)

    def duration(self, seconds: float) -> Any:
        sec, nanosec = self._split(seconds)
        return self.store.types["builtin_interfaces/msg/Duration"](sec=sec, nanosec=nanosec)

    def header(self, stamp: float, frame_id: str) -> Any:
        return self.store.types["std_msgs/msg/Header"](stamp=self.time(stamp), frame_id=frame_id)

    def _encoder(self, ros_type: str) -> Encoder:
        """Hub message -> the rosbags message of ``ros_type``, by the ``.msg`` fields."""
        found = self._encoders.get(ros_type)
        if found is None:
            found = message_encoder(ros_type, self.store.types.__getitem__, self._split)
            self._encoders[ros_type] = found
        return found

    def _plan(self, plan: hm.Plan) -> Any:
        return self._encoder(msgs.PLAN)(plan)

    def convert(self, hub_msg: object) -> list[tuple[str, str, Any]]:
        """Hub message -> ``[(bag topic suffix, msgtype, ROS message)]``.

        The first entry goes on the hub topic; a second one, if any, carries the
        project's extra fields on the same topic under :data:`BRIDGE_PREFIX`.
        """
        m = hub_msg
        if isinstance(m, hm.ActionExecution):
            extra = self._encoder(msgs.BRIDGE_ACTION_EXECUTION)(hm.BridgeActionExecution.of(m))
            return [
                ("", msgs.ACTION_EXECUTION, extra.execution),
                (BRIDGE_PREFIX, msgs.BRIDGE_ACTION_EXECUTION, extra),
            ]
        if isinstance(m, hm.ExecutingPlan):
            extra = self._encoder(msgs.BRIDGE_EXECUTING_PLAN)(m)
            return [("", msgs.PLAN, extra.plan), (BRIDGE_PREFIX, msgs.BRIDGE_EXECUTING_PLAN, extra)]
        if isinstance(m, hm.DotGraph):
            return [("", msgs.STRING, self.store.types[msgs.STRING](data=m.text))]
        for cls, ros_type in _PLAIN:
            if isinstance(m, cls):
                return [("", ros_type, self._encoder(ros_type)(m))]
        return []

    def _callback(self, hub_topic: str) -> Callable[[object], None]:
        topic = bag_topic(hub_topic)

        def on_message(msg: object) -> None:
            if not self.recording:
                return
            converted = self.convert(msg)
            if not converted:
                self.dropped += 1
                log.warning("%s: not recording %s on %s", self.path, type(msg).__name__, topic)
                return
            stamp = self.clock.now()
            try:
                for prefix, msgtype, ros in converted:
                    self.record(prefix + topic, msgtype, ros, stamp)
            except RecorderError:
                # A hub callback must not take the transport down with it.
                self.dropped += 1
                log.exception("%s: recording %s failed", self.path, topic)

        return on_message

    def summary(self) -> Mapping[str, int]:
        """Messages written per bag topic so far."""
        with self._lock:
            return dict(self.counts)


def _zeros9() -> Any:
    return np.zeros(9, dtype=np.float64)
