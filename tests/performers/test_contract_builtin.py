"""Every built-in performer passes the performer contract (plansys_bridge.testing)."""

from __future__ import annotations

from pathlib import Path

from plansys_bridge.clock import Clock, WallClock
from plansys_bridge.hub.hub import Hub
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.testing import PerformerContract

BAGS = Path(__file__).resolve().parents[2] / "bags"
CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BT_TREES = Path(__file__).resolve().parents[1] / "data" / "bt"


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
    bad_settings = [
        ({"topic": 5}, "topic"),
        ({"colour": "red"}, "colour"),
        ({"rate": 0}, "rate"),
        ({"segments": []}, "segments"),
        ({"segments": "no_such.segments.yaml"}, "segments"),
        ({"knowledge": {"functions": {"heading": "h"}}}, "knowledge.functions"),
        ({"knowledge": {"functions": {"x": "rx"}, "period": 0}}, "knowledge.period"),
    ]

    def make_context(self, hub: Hub) -> PerformerContext:
        return PerformerContext(hub=hub, clock=hub.clock, base_dir=BAGS)


class TestMavlinkContract(PerformerContract):
    """The MAVLink performer driving the vehicle double (a rover, 10x speed) over TCP."""

    entry = {
        "kind": "mavlink",
        "name": "rover1",
        "vehicle": "r1",
        "double": {"model": "rover", "speedup": 10, "ekf_delay": 1.0},
        "locations": "mavlink_locations.yaml",
        "actions": {"drive": []},
        "commands": {"drive": {"do": "goto", "vehicle_arg": 0, "target_arg": 2}},
        "heartbeat_period": 0.2,
        "feedback_period": 0.05,
        "timeouts": {"heartbeat": 2.0, "command": 1.0, "ekf": 30, "arm": 10, "action": 60},
    }
    goal = ("drive", ("r1", "yard", "east_field"))
    failing_goal = ("drive", ("r1", "yard", "moon"))
    bad_settings = [
        ({"double": None, "url": "tpc:127.0.0.1:5760"}, "url"),
        ({"timeouts": {"ekf": 0}}, "timeouts.ekf"),
        ({"commands": {"drive": {"do": "teleport"}}}, "commands.drive.do"),
    ]
    cancel_within = 10.0
    action_timeout = 90.0

    def make_clock(self) -> Clock:
        return WallClock()  # a vehicle runs in real time

    def make_context(self, hub: Hub) -> PerformerContext:
        return PerformerContext(hub=hub, clock=hub.clock, base_dir=CONFIGS)


class TestBtContract(PerformerContract):
    """The behaviour-tree performer running PlanSys2's example transport tree (grippers,
    approach, move) with the example node plugins."""

    entry = {
        "kind": "bt",
        "name": "r2d2_bt",
        "actions": {"transport": ["r2d2"]},
        "trees": {"transport": "transport.xml"},
        "plugins": ["bt_example_nodes"],
        "tick_period": 0.5,
    }
    goal = ("transport", ("r2d2", "wheel_1", "wheels_zone", "assembly_zone"))
    failing_goal = ("transport", ("r2d2", "wheel_1", "wheels_zone", "nowhere"))
    bad_settings = [
        ({"tick_period": 0}, "tick_period"),
        ({"tick_period": "fast"}, "tick_period"),
        ({"trees": {"transport": 5}}, "trees.transport"),
        ({"trees": {"transport": "transport.xml", "fly": "fly.xml"}}, "trees.fly"),
        ({"trees": {"transport": "no_such_tree.xml"}}, "trees.transport"),
        ({"trees": None}, "trees"),
        ({"plugins": ["no_such_bt_plugin_module"]}, "plugins[0]"),
        ({"plugins": "bt_example_nodes"}, "plugins"),
        ({"colour": "red"}, "colour"),
    ]

    def make_context(self, hub: Hub) -> PerformerContext:
        return PerformerContext(hub=hub, clock=hub.clock, base_dir=BT_TREES)
