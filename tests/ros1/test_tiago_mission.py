"""configs/tiago_ros1.yaml end to end on a real roscore: the project's move_base double,
the ros1_move_base performer, the planner and executor, and the mission's bridge
carrying the robot's odometry to a ROS 2 (Cyclone DDS) reader while it drives."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest
import yaml

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import mission_from_dict
from plansys_bridge.ros1.roscore import Roscore

REPO = Path(__file__).resolve().parents[2]
CONFIG = REPO / "configs" / "tiago_ros1.yaml"


def mission_for(core: Roscore, domain_id: int) -> Any:
    text = CONFIG.read_text().replace("http://127.0.0.1:11311", core.uri)
    data = yaml.safe_load(text)
    data["bridge"]["ros2"]["domain_id"] = domain_id
    return mission_from_dict(data, source=str(CONFIG), base_dir=CONFIG.parent)


@pytest.mark.allow_threads("Dummy-")
def test_tiago_mission_drives_move_base_and_bridges_odom(roscore: Roscore) -> None:
    pytest.importorskip("cyclonedds")
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    from plansys_bridge.hub.dds_config import loopback_config
    from plansys_bridge.hub.dds_participant import SharedDomain
    from plansys_bridge.interfaces.dds import dds_type

    domain_id = 78
    SharedDomain.acquire(domain_id, loopback_config(domain_id))  # the config the bridge uses
    double = subprocess.Popen(
        [sys.executable, "-m", "plansys_bridge_adapters.ros1.double", "--speed", "4"],
        env=roscore.env() | {"PYTHONPATH": os.environ.get("PYTHONPATH", "")},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        assert double.stdout is not None
        assert double.stdout.readline().startswith("move_base double at /move_base")
        lines: list[str] = []
        drain = threading.Thread(target=lambda: lines.extend(double.stdout or []), daemon=True)
        drain.start()
        mission = mission_for(roscore, domain_id)
        said: list[str] = []
        participant = DomainParticipant(domain_id)
        odom = DataReader(
            participant,
            Topic(participant, "rt/odom", dds_type("nav_msgs/msg/Odometry")),
            Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll),
        )
        report = run_mission(mission, out=said.append)
        samples = odom.take(10000)
    finally:
        double.terminate()
        double.wait(timeout=20)
        SharedDomain.release(domain_id)
    assert report.success, report.summary()
    result = report.result
    assert result is not None
    assert [a.performer for a in result.actions] == ["tiago_nav"] * len(result.actions)
    assert any("bridge: 3 topics" in s for s in said)
    assert samples, "no odometry crossed the bridge"
    xs = [s.pose.pose.position.x for s in samples]
    assert max(xs) > 3.9  # the robot reached the livingroom / bedroom side (x = 4)
    assert samples[-1].header.frame_id == "odom"
    log = "".join(lines)
    assert log.count("SUCCEEDED") == len(result.actions)


def test_mission_bridge_section_is_checked_on_load(tmp_path: Path) -> None:
    data = yaml.safe_load(CONFIG.read_text())
    data["bridge"]["topics"][0]["from"] = "ros3"
    with pytest.raises(ConfigError) as info:
        mission_from_dict(data, source="m.yaml", base_dir=CONFIG.parent)
    assert str(info.value).startswith("m.yaml:bridge.topics[0].from: must be ros1 or ros2")


def test_bridge_command_reads_a_mission_file(tmp_path: Path) -> None:
    from plansys_bridge.bridge.config import load_bridge_config

    config = load_bridge_config(CONFIG)
    assert [r.target for r in config.routes] == ["/tf", "/odom", "/nav_vel"]
    tiago = load_bridge_config(REPO / "configs" / "tiago_bridge.yaml")
    assert {r.source for r in tiago.routes} == {
        "/tf",
        "/tf_static",
        "/scan",
        "/mobile_base_controller/odom",
        "/base_imu",
        "/nav_vel",
    }
    empty = tmp_path / "m.yaml"
    empty.write_text("name: x\ndomain: [d.pddl]\nperformers: []\n")
    with pytest.raises(ConfigError, match="no bridge: section"):
        load_bridge_config(empty)
