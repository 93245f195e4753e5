"""The shipped missions against a real ArduPilot SITL (skipped unless one is given).

Start SITL (any speedup; ``--speedup 1`` and ``--speedup 5`` are both expected to
pass from a fresh boot, EKF wait included) and point the tests at it::

    sim_vehicle.py -v ArduCopter -I0 --speedup 5     # tcp:127.0.0.1:5760
    sim_vehicle.py -v Rover -I1 --speedup 5          # tcp:127.0.0.1:5770
    ARDUPILOT_SITL_COPTER_URL=tcp:127.0.0.1:5760 \\
    ARDUPILOT_SITL_ROVER_URL=tcp:127.0.0.1:5770 pytest -m sitl tests/adapters/mavlink
"""

from __future__ import annotations

import os
from typing import Any

import pytest
import yaml
from mavlink_support import CONFIGS

from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import mission_from_dict

COPTER_URL = os.environ.get("ARDUPILOT_SITL_COPTER_URL", "")
ROVER_URL = os.environ.get("ARDUPILOT_SITL_ROVER_URL", "")
SITL_TIMEOUTS = {"connect": 60, "heartbeat": 5, "command": 2, "ekf": 300, "arm": 120, "action": 600}

pytestmark = pytest.mark.sitl


def _with_urls(name: str, urls: dict[str, str]) -> dict[str, Any]:
    data = yaml.safe_load((CONFIGS / name).read_text())
    for entry in data["performers"]:
        entry.pop("double", None)
        entry["url"] = urls[entry["model"]]
        entry["timeouts"] = SITL_TIMEOUTS
    data["timeout"] = 1800
    return data


def _run(name: str, urls: dict[str, str]) -> None:
    mission = mission_from_dict(_with_urls(name, urls), source=name, base_dir=CONFIGS)
    lines: list[str] = []
    report = run_mission(mission, out=lines.append)
    assert report.success, report.summary() + "\n" + "\n".join(lines)


@pytest.mark.skipif(
    not COPTER_URL,
    reason="set ARDUPILOT_SITL_COPTER_URL (e.g. tcp:127.0.0.1:5760) to fly a real ArduCopter SITL",
)
def test_copter_mission_on_sitl() -> None:
    _run("mavlink_copter.yaml", {"copter": COPTER_URL})


@pytest.mark.skipif(
    not ROVER_URL,
    reason="set ARDUPILOT_SITL_ROVER_URL (e.g. tcp:127.0.0.1:5770) to drive a real ArduRover SITL",
)
def test_rover_mission_on_sitl() -> None:
    _run("mavlink_rover.yaml", {"rover": ROVER_URL})


@pytest.mark.skipif(
    not (COPTER_URL and ROVER_URL),
    reason="set both ARDUPILOT_SITL_COPTER_URL and ARDUPILOT_SITL_ROVER_URL for the fleet mission",
)
def test_fleet_mission_on_sitl() -> None:
    _run("mavlink_fleet.yaml", {"copter": COPTER_URL, "rover": ROVER_URL})
