"""ROS 2 topic fields as sensing sources, over Cyclone DDS on loopback: the writer is
typed in this test from upstream's std_msgs/msg/Float32.msg (``float32 data``) with
ROS 2's DDS names, not from the project's generated types."""

from __future__ import annotations

import asyncio
import random
from dataclasses import dataclass

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from ros_rules import engine, knowledge, wait_until

from plansys_bridge.errors import ConfigError


@dataclass
class Float32_(IdlStruct, typename="std_msgs::msg::dds_::Float32_"):
    data: float32 = 0.0


def test_a_ros2_topic_sets_a_predicate_and_a_function() -> None:
    domain_id = random.SystemRandom().randint(100, 200)
    k = knowledge()
    rules = (
        {
            "from": "ros2",
            "topic": "/r2d2/battery",
            "type": "std_msgs/msg/Float32",
            "domain_id": domain_id,
            "when": "data < 0.25",
            "clear_when": "data > 0.35",
            "predicate": "(battery_low r2d2)",
        },
        {
            "from": "ros2",
            "topic": "/r2d2/battery",
            "type": "std_msgs/msg/Float32",
            "domain_id": domain_id,
            "field": "data * 100",
            "function": "(battery_level r2d2)",
        },
    )

    async def main() -> None:
        sensing = engine(k, *rules)
        sensing.start({})
        try:
            participant = DomainParticipant(domain_id)
            writer = DataWriter(participant, Topic(participant, "rt/r2d2/battery", Float32_))
            for value in (0.5, 0.3, 0.2):
                await asyncio.sleep(0.3)
                writer.write(Float32_(value))
            await wait_until(lambda: k.exist_predicate("(battery_low r2d2)"))
            await wait_until(lambda: k.get_function("(battery_level r2d2)") == pytest.approx(20))
        finally:
            sensing.stop()

    asyncio.run(main())


def test_an_unknown_type_or_field_is_a_load_error() -> None:
    k = knowledge()
    bad_type = {
        "from": "ros2",
        "topic": "/b",
        "type": "std_msgs/msg/Float",
        "function": "(battery_level r2d2)",
        "field": "data",
    }
    with pytest.raises(ConfigError, match=r"sensing\[0\]\.type: unknown ROS 2 message type"):
        engine(k, bad_type)
    bad_field = {
        "from": "ros2",
        "topic": "/b",
        "type": "sensor_msgs/msg/BatteryState",
        "when": "cell_voltage[2] < 3.3 and percentge < 0.2",
        "predicate": "(battery_low r2d2)",
    }
    with pytest.raises(ConfigError, match=r"sensing\[0\]\.when: no field 'percentge'"):
        engine(k, bad_field)
