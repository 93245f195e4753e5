"""``ros_discovery_info``: how ROS 2 tools learn which nodes own which DDS endpoints.

A ROS 2 process (rmw_cyclonedds and the other RMWs, through rmw_dds_common) publishes
one ``rmw_dds_common/msg/ParticipantEntitiesInfo`` per DDS participant on the DDS
topic ``ros_discovery_info`` (no ``rt/`` prefix), reliable, transient-local, keep
last 1: the participant's GID and, per node, its namespace, name and the GIDs of its
readers and writers. ``ros2 node list`` and ``ros2 topic list -v`` read it to put
node names on what DDS discovery shows. A GID here is the entity's 16-byte DDS GUID
(``Gid.msg``: ``char[16] data``, ROS 2 Jazzy).

The type comes from the vendored ``rmw_dds_common`` texts like every other.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Any

from cyclonedds.core import Policy, Qos
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from plansys_bridge.interfaces.dds import dds_type

__all__ = ["DISCOVERY_TOPIC", "node_name_for", "publish_discovery_info"]

DISCOVERY_TOPIC = "ros_discovery_info"
PARTICIPANT_ENTITIES_INFO = "rmw_dds_common/msg/ParticipantEntitiesInfo"
_NOT_NAME = re.compile(r"[^A-Za-z0-9_]")


def node_name_for(text: str) -> str:
    """A valid ROS node name from ``text`` (letters, digits, underscores; no leading digit)."""
    name = _NOT_NAME.sub("_", text) or "plansys_bridge"
    return name if not name[0].isdigit() else f"n_{name}"


def _gid(entity: Any) -> Any:
    return dds_type("rmw_dds_common/msg/Gid")(data=list(entity.guid.bytes))


def publish_discovery_info(
    participant: Any, node_name: str, readers: Iterable[Any], writers: Iterable[Any]
) -> tuple[Any, Any]:
    """Write this participant's one-node ``ParticipantEntitiesInfo``.

    Returns the (writer, topic) to delete before the participant; the writer keeps the
    sample (transient-local) for tools that start later.
    """
    info_type = dds_type(PARTICIPANT_ENTITIES_INFO)
    node_type = dds_type("rmw_dds_common/msg/NodeEntitiesInfo")
    topic = Topic(participant, DISCOVERY_TOPIC, info_type)
    writer = DataWriter(
        participant,
        topic,
        Qos(
            Policy.Reliability.Reliable(duration(seconds=1)),
            Policy.Durability.TransientLocal,
            Policy.History.KeepLast(1),
            Policy.DataRepresentation(use_cdrv0_representation=True),
        ),
    )
    node = node_type(
        node_namespace="/",
        node_name=node_name_for(node_name),
        reader_gid_seq=[_gid(r) for r in readers],
        writer_gid_seq=[_gid(w) for w in writers],
    )
    writer.write(info_type(gid=_gid(participant), node_entities_info_seq=[node]))
    return writer, topic
