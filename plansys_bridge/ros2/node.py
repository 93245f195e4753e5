"""A ROS 2 node's DDS side: one participant, its readers handed to asyncio.

ROS 2 services and actions (:mod:`plansys_bridge.ros2.services`,
:mod:`plansys_bridge.ros2.actions`) are plain DDS topics with ROS 2's names and
types, so all they need from the node is a participant to create topics, writers and
readers on, and a way to have each received sample processed on the asyncio loop.
One thread per node waits on a DDS wait set over every reader and hands each valid
sample to its reader's callback with ``call_soon_threadsafe``: callbacks run on the
loop, in arrival order per reader, never on the DDS thread.

The participant, its thread, the shared domain and the QoS are those of the hub's DDS
transport (:mod:`plansys_bridge.hub.dds_participant`): Cyclone allows one creation
of a domain id per process, so both must be given the same configuration
(loopback-only by default).
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from cyclonedds.core import (
    DDSException,
    InstanceState,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
)
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from plansys_bridge.errors import HubError
from plansys_bridge.hub.dds_config import check_domain_id, loopback_config
from plansys_bridge.hub.dds_participant import DdsParticipant, endpoint_qos

__all__ = [
    "ACTION_STATUS_QOS",
    "DEFAULT_QOS",
    "SERVICES_QOS",
    "EndpointQos",
    "Ros2Node",
    "SampleCallback",
]

log = logging.getLogger(__name__)

SampleCallback = Callable[[Any], None]
"""Called on the loop with one valid sample (its ``sample_info`` attached)."""

_ANY_SAMPLE = SampleState.Any | ViewState.Any | InstanceState.Any
_WAIT_NS = duration(seconds=1)
_TAKE_BATCH = 64


@dataclass(frozen=True)
class EndpointQos:
    """The ROS 2 QoS profile of one endpoint (rmw's history, reliability, durability).

    ``SERVICES_QOS`` is ``rmw_qos_profile_services_default`` (keep last 10, reliable,
    volatile), ``DEFAULT_QOS`` is ``rmw_qos_profile_default`` (the same for topics,
    used for action feedback) and ``ACTION_STATUS_QOS`` is rcl_action's
    ``rcl_action_qos_profile_status_default`` (keep last 1, reliable,
    transient-local; rcl_action/include/rcl_action/default_qos.h).
    """

    depth: int = 10
    transient_local: bool = False

    def qos(self, *, user_data: bytes | None = None) -> Qos:
        return endpoint_qos(
            depth=self.depth, transient_local=self.transient_local, user_data=user_data
        )


SERVICES_QOS = EndpointQos(10)
DEFAULT_QOS = EndpointQos(10)
ACTION_STATUS_QOS = EndpointQos(1, transient_local=True)


@dataclass
class _Reader:
    topic_name: str
    reader: Any
    condition: Any
    callback: SampleCallback


class Ros2Node:
    """A DDS participant for ROS 2 services and actions, on the loopback config by default.

    ``start()`` on the running loop before creating endpoints; ``close()`` stops the
    reader thread and deletes every entity. ``name`` is only for logs and thread names.
    """

    def __init__(
        self, domain_id: int = 0, *, config: str | None = None, name: str = "plansys_bridge"
    ) -> None:
        self.domain_id = check_domain_id(domain_id)
        self.config = config if config is not None else loopback_config(domain_id)
        self.name = name
        self._loop: asyncio.AbstractEventLoop | None = None
        self._dds = DdsParticipant(self.domain_id, self.config, f"ros2-node-{name}")
        self._topics: dict[str, Any] = {}
        self._readers: list[_Reader] = []
        self._writers: list[Any] = []
        self._lock = threading.Lock()
        self.dropped = 0
        """Samples that could not be read (a peer's malformed data)."""

    @property
    def participant(self) -> Any:
        if self._dds.participant is None:
            raise HubError(f"ROS 2 node {self.name}: start it first")
        return self._dds.participant

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        if self._loop is None:
            raise HubError(f"ROS 2 node {self.name}: start it first")
        return self._loop

    async def start(self) -> None:
        if self._dds.running:
            return
        self._loop = asyncio.get_running_loop()
        try:
            self._dds.open()
        except BaseException:
            self._teardown()
            raise
        self._dds.start(self._poll)

    async def close(self) -> None:
        self._teardown()

    def _teardown(self) -> None:
        with self._lock:
            entities: list[Any] = []
            for r in self._readers:
                entities += [r.condition, r.reader]
            entities += self._writers
            entities += list(self._topics.values())
            self._readers.clear()
            self._writers.clear()
            self._topics.clear()
        self._dds.close(entities)

    # -- endpoints ---------------------------------------------------------------------
    def topic(self, name: str, idl_type: type[Any]) -> Any:
        """The DDS topic ``name`` (one per name and node)."""
        with self._lock:
            topic = self._topics.get(name)
            if topic is None:
                try:
                    topic = Topic(self.participant, name, idl_type)
                except DDSException as exc:
                    raise HubError(f"{name}: cannot create DDS topic: {exc}") from exc
                self._topics[name] = topic
            return topic

    def writer(
        self, name: str, idl_type: type[Any], qos: EndpointQos, user_data: bytes | None = None
    ) -> Any:
        topic = self.topic(name, idl_type)
        try:
            writer = DataWriter(self.participant, topic, qos.qos(user_data=user_data))
        except DDSException as exc:
            raise HubError(f"{name}: cannot create DDS writer: {exc}") from exc
        with self._lock:
            self._writers.append(writer)
        return writer

    def reader(
        self,
        name: str,
        idl_type: type[Any],
        qos: EndpointQos,
        callback: SampleCallback,
        user_data: bytes | None = None,
    ) -> Any:
        """A reader whose samples go to ``callback`` on the loop."""
        topic = self.topic(name, idl_type)
        try:
            reader = DataReader(self.participant, topic, qos.qos(user_data=user_data))
            condition = ReadCondition(reader, _ANY_SAMPLE)
        except DDSException as exc:
            raise HubError(f"{name}: cannot create DDS reader: {exc}") from exc
        with self._lock:
            self._readers.append(_Reader(name, reader, condition, callback))
            self._dds.attach(condition)
        return reader

    def remove(self, *entities: Any) -> None:
        """Delete writers and readers made by this node (a closed client or server)."""
        with self._lock:
            for entity in entities:
                for r in [r for r in self._readers if r.reader is entity]:
                    self._readers.remove(r)
                    self._dds.detach(r.condition)
                    r.condition.__del__()
                if entity in self._writers:
                    self._writers.remove(entity)
                entity.__del__()

    # -- receiving ---------------------------------------------------------------------
    def _poll(self) -> None:
        with self._lock:
            readers = list(self._readers)
        for r in readers:
            self._take(r)

    def _take(self, r: _Reader) -> None:
        loop = self.loop
        while True:
            try:
                samples = r.reader.take(N=_TAKE_BATCH)
            except DDSException:  # the reader was removed meanwhile
                return
            except Exception as exc:  # a peer's malformed sample
                self.dropped += 1
                log.warning("%s: cannot read a sample: %s", r.topic_name, exc)
                return
            if not samples:
                return
            for sample in samples:
                if sample.sample_info.valid_data:
                    loop.call_soon_threadsafe(r.callback, sample)
