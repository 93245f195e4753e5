"""The ``ros1_move_base`` performer keeps the performer contract, against Debian's
roscore and the rospy actionlib move_base double the other ROS 1 tests use
(tests/ros1/peers/move_base_double.py), one double per test."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, ClassVar

import pytest

from plansys_bridge.clock import Clock, WallClock
from plansys_bridge.ros1.roscore import Roscore
from plansys_bridge.testing import PerformerContract

NS = "/contract_move_base"
ENTRY: dict[str, Any] = {
    "kind": "ros1_move_base",
    "name": "tiago_nav",
    "actions": {"move": ["tiago"]},
    "action_ns": NS,
    "locations": {
        "kitchen": {"x": 0.0, "y": 0.0, "yaw": 0.0},
        "livingroom": {"x": 2.0, "y": 1.0, "yaw": 1.57},  # 2.2 m: about 1 s at 2 m/s
        "bathroom": {"x": -60.0, "y": 0.0},  # the double aborts: "no path to goal"
    },
}


class TestMoveBaseContract(PerformerContract):
    entry: ClassVar[dict[str, Any]] = ENTRY
    goal = ("move", ("tiago", "kitchen", "livingroom"))
    failing_goal = ("move", ("tiago", "kitchen", "bathroom"))
    bad_settings = [
        ({"master_uri": "localhost:11311"}, "master_uri"),
        ({"action_ns": "not a topic"}, "action_ns"),
        ({"locations": {"hall": {"x": 1.0}}}, "locations.hall.y"),
        ({"locations": {"hall": {"x": 1.0, "y": True}}}, "locations.hall.y"),
        ({"locations": []}, "locations"),
        ({"locations": "places.yaml"}, "locations"),
        ({"target_arg": "last"}, "target_arg"),
        ({"frame_id": ""}, "frame_id"),
        ({"colour": "red"}, "colour"),
    ]
    action_timeout = 60.0

    @pytest.fixture(autouse=True)
    def _move_base(self, roscore: Roscore, start_peer: Any) -> Iterator[None]:
        self.entry = {**ENTRY, "master_uri": roscore.uri}  # type: ignore[misc]
        start_peer("move_base_double.py", NS, "2")
        yield

    def make_clock(self) -> Clock:
        return WallClock()  # roscore and move_base run in real time
