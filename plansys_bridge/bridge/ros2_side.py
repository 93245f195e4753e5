"""The bridge's ROS 2 side: Cyclone DDS with ROS 2's names, on the hub's loopback config.

A ROS 2 topic ``/name`` is the DDS topic ``rt/name`` with the type
``pkg::msg::dds_::Type_`` serialised XCDR1 (the classes come from
:func:`plansys_bridge.interfaces.dds.dds_type`). Messages cross as bytes: rosbags'
ROS 2 typestore writes the CDR a ROS 2 node would, the DDS class reads it back, and
the reverse on the way in, so the bridge needs no per-type code.

DDS calls the reader listener on its own thread; each sample is handed to the
asyncio loop (``call_soon_threadsafe``), where the ROS 1 side publishes it.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from typing import Any

from cyclonedds.core import Listener, Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from plansys_bridge.bridge.config import Qos as QosConfig
from plansys_bridge.hub.dds_config import loopback_config
from plansys_bridge.hub.dds_participant import SharedDomain
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.interfaces.typestore import ros2_typestore

__all__ = ["Ros2Side", "dds_qos", "ros2_topic"]

log = logging.getLogger(__name__)


def ros2_topic(name: str) -> str:
    """``/odom`` -> ``rt/odom`` (ROS 2's DDS topic name)."""
    return "rt/" + name.lstrip("/")


def dds_qos(qos: QosConfig) -> Qos:
    reliability = (
        Policy.Reliability.Reliable(duration(seconds=1))
        if qos.reliability == "reliable"
        else Policy.Reliability.BestEffort
    )
    durability = (
        Policy.Durability.TransientLocal
        if qos.durability == "transient_local"
        else Policy.Durability.Volatile
    )
    return Qos(
        reliability,
        durability,
        Policy.History.KeepLast(qos.depth),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


class Ros2Side:
    """One DDS participant on ``domain_id``; writers and readers by ROS 2 topic name."""

    def __init__(self, domain_id: int) -> None:
        self.domain_id = domain_id
        self.store = ros2_typestore()
        SharedDomain.acquire(domain_id, loopback_config(domain_id))
        self._participant: DomainParticipant | None = DomainParticipant(domain_id)
        self._entities: list[Any] = []

    def close(self) -> None:
        self._entities.clear()
        if self._participant is not None:
            self._participant = None
            SharedDomain.release(self.domain_id)

    def _topic(self, name: str, type_name: str) -> Topic:
        assert self._participant is not None
        return Topic(self._participant, ros2_topic(name), dds_type(type_name))

    def writer(self, name: str, type_name: str, qos: QosConfig) -> Callable[[Any], None]:
        """A function writing a rosbags ROS 2 message of ``type_name`` on ``name``."""
        assert self._participant is not None
        cls = dds_type(type_name)
        writer = DataWriter(self._participant, self._topic(name, type_name), dds_qos(qos))
        self._entities.append(writer)
        store = self.store

        def write(msg: Any) -> None:
            writer.write(cls.deserialize(bytes(store.serialize_cdr(msg, type_name))))

        return write

    def reader(
        self,
        name: str,
        type_name: str,
        qos: QosConfig,
        callback: Callable[[Any], None],
        loop: asyncio.AbstractEventLoop,
    ) -> DataReader:
        """Call ``callback`` on ``loop`` with each sample as a rosbags ROS 2 message."""
        assert self._participant is not None
        store = self.store

        def deliver(raw: bytes) -> None:
            try:
                msg = store.deserialize_cdr(raw, type_name)
            except Exception as exc:
                log.warning(
                    "ROS 2 topic %s: undecodable %s sample dropped: %s", name, type_name, exc
                )
                return
            callback(msg)

        def on_data(reader: DataReader) -> None:
            for sample in reader.take(64):
                if not isinstance(sample, IdlStruct):
                    continue  # an InvalidSample: a writer went away (no data)
                raw = sample.serialize()
                with contextlib.suppress(RuntimeError):  # the loop closed while stopping
                    loop.call_soon_threadsafe(deliver, raw)

        reader = DataReader(
            self._participant,
            self._topic(name, type_name),
            dds_qos(qos),
            listener=Listener(on_data_available=on_data),
        )
        self._entities.append(reader)
        return reader
