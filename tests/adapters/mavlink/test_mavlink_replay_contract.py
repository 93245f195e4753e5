"""The ``mavlink_replay`` performer passes the performer contract on the project's
recorded flight (``bags/logs/copter1.tlog``, written by tests/data/logs/generate.py).

The recording switches to RTL at 45.3 s, inside the stretch that serves the flight
home, so that call is the contract's failing goal: the performer must fail it and
say why.
"""

from __future__ import annotations

from pathlib import Path

from plansys_bridge.hub.hub import Hub
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.testing import PerformerContract

LOGS = Path(__file__).resolve().parents[3] / "bags" / "logs"


class TestMavlinkReplayContract(PerformerContract):
    entry = {
        "kind": "mavlink_replay",
        "name": "copter1",
        "actions": {"takeoff": ["copter1"], "fly": ["copter1"]},
        "log": "copter1.tlog",
        "rate": 1.0,
        "segments": [
            {"action": "(takeoff copter1 pad)", "start": 0, "end": 10},
            {"action": "(fly copter1 pad field)", "start": 10, "end": 40},
            {"action": "(fly copter1 field pad)", "start": 40, "end": 70},
        ],
    }
    goal = ("fly", ("copter1", "pad", "field"))
    failing_goal = ("fly", ("copter1", "field", "pad"))
    bad_settings = [
        ({"rate": -1}, "rate"),
        ({"log": "no_such_flight.tlog"}, "log"),
        (
            {"segments": [{"action": "(fly copter1 pad field)", "start": 5, "end": 900}]},
            "segments[0].end",
        ),
        ({"colour": "red"}, "colour"),
    ]

    def make_context(self, hub: Hub) -> PerformerContext:
        return PerformerContext(hub=hub, clock=hub.clock, base_dir=LOGS)
