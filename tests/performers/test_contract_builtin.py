"""Every built-in performer passes the performer contract (plansys_bridge.testing)."""

from __future__ import annotations

from pathlib import Path

from plansys_bridge.hub.hub import Hub
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.testing import PerformerContract

BAGS = Path(__file__).resolve().parents[2] / "bags"


class TestSimulatedContract(PerformerContract):
    entry = {
        "kind": "simulated",
        "name": "r1_base",
        "actions": {"move": ["r1"]},
        "durations": {"move": 4.0},
        "feedback_period": 0.5,
    }
    goal = ("move", ("r1", "a", "b"))
    bad_settings = [
        ({"durations": {"move": -1}}, "durations.move"),
        ({"colour": "red"}, "colour"),
        ({"actions": None}, "actions"),
    ]


class TestCanContract(PerformerContract):
    """The CAN base on python-can's virtual bus, driving the simulated base."""

    entry = {
        "kind": "can",
        "name": "base_r2d2",
        "robot": "r2d2",
        "actions": {"move": {"robot": 0, "destination": 2}},
        "locations": {"dock": [0.0, 0.0, 0.0], "hall": [3.0, 0.0]},
        "bus": {"interface": "virtual", "channel": "contract_can0"},
        "simulate_base": {"x": 0.0, "y": 0.0},
    }
    goal = ("move", ("r2d2", "dock", "hall"))
    failing_goal = ("move", ("r2d2", "dock", "attic"))
    bad_settings = [
        ({"bus": {"interface": "socketcann"}}, "bus.interface"),
        ({"robot": None}, "robot"),
        ({"safety": {"heartbeat_timout": 1}}, "safety.heartbeat_timout"),
    ]


class TestRosbagContract(PerformerContract):
    """The bag-replay navigation performer on the project's generated demo bag."""

    entry = {
        "kind": "rosbag",
        "name": "tiago_nav",
        "actions": {"move": ["tiago"]},
        "bag": "kitchen_nav",
        "topic": "/odom",
        "segments": "kitchen_nav.segments.yaml",
    }
    goal = ("move", ("tiago", "kitchen", "livingroom"))
    failing_goal = ("move", ("tiago", "kitchen", "attic"))
    bad_settings = [({"topic": 5}, "topic"), ({"colour": "red"}, "colour")]

    def make_context(self, hub: Hub) -> PerformerContext:
        return PerformerContext(hub=hub, clock=hub.clock, base_dir=BAGS)
