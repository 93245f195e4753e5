"""rmw_dds_common's discovery messages as DDS types, typed from upstream's texts (Jazzy):

Gid.msg:                     char[16] data
NodeEntitiesInfo.msg:        string<=256 node_namespace / string<=256 node_name /
                             Gid[] reader_gid_seq / Gid[] writer_gid_seq
ParticipantEntitiesInfo.msg: Gid gid / NodeEntitiesInfo[] node_entities_info_seq

(``char`` is uint8 in ROS 2's IDL.) No ``from __future__ import annotations``:
cyclonedds reads the annotations.
"""

from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, bounded_str, sequence, uint8


@dataclass
class Gid_(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    data: array[uint8, 16] = field(default_factory=lambda: [0] * 16)


@dataclass
class NodeEntitiesInfo_(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    node_namespace: bounded_str[256] = ""
    node_name: bounded_str[256] = ""
    reader_gid_seq: sequence[Gid_] = field(default_factory=list)
    writer_gid_seq: sequence[Gid_] = field(default_factory=list)


@dataclass
class ParticipantEntitiesInfo_(
    IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"
):
    gid: Gid_ = field(default_factory=Gid_)
    node_entities_info_seq: sequence[NodeEntitiesInfo_] = field(default_factory=list)
