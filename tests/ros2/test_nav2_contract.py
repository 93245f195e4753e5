"""The ``ros2_nav2`` performer keeps the performer contract, against the independent
NavigateToPose server of the Nav2 tests (tests/nav2_peer.py: plain Cyclone DDS,
types from the upstream texts), one server and DDS domain per test."""

from __future__ import annotations

import random
from collections.abc import Iterator
from typing import Any, ClassVar

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from nav2_peer import ServerThread

from plansys_bridge.clock import Clock, WallClock
from plansys_bridge.testing import PerformerContract

ENTRY: dict[str, Any] = {
    "kind": "ros2_nav2",
    "name": "tb3_nav",
    "actions": {"move": ["r1"]},
    "frame_id": "map",
    "locations": {
        "hall": {"x": 0.0, "y": 0.0},
        "kitchen": {"x": 4.0, "y": 1.0, "yaw": 1.57},  # the peer: 3, 2, 1, 0 m, SUCCEEDED
        "bedroom": {"x": 9.0, "y": 0.0},  # the peer: ABORTED, error_code 204
    },
}


class TestNav2Contract(PerformerContract):
    """A goal takes the peer 2 s (four 0.5 s steps), so a CANCEL meets it running."""

    entry: ClassVar[dict[str, Any]] = ENTRY
    goal = ("move", ("r1", "hall", "kitchen"))
    failing_goal = ("move", ("r1", "hall", "bedroom"))
    bad_settings = [
        ({"locations": {"hall": {"x": 1.0}}}, "locations.hall.y"),
        ({"locations": {"hall": {"x": 1.0, "y": 2.0, "z": 0}}}, "locations.hall.z"),
        ({"locations": 5}, "locations"),
        ({"locations": "no_such_places.yaml"}, "locations"),
        ({"target_arg": "last"}, "target_arg"),
        ({"domain_id": -1}, "domain_id"),
        ({"action_name": "/"}, "action_name"),
        ({"double": {"speed": 0}}, "double.speed"),
        ({"double": {"blocked": ["attic"]}}, "double.blocked[0]"),
        ({"colour": "red"}, "colour"),
    ]
    action_timeout = 60.0

    @pytest.fixture(autouse=True)
    def _nav2_server(self) -> Iterator[None]:
        domain = random.SystemRandom().randint(1, 232)
        self.entry = {**ENTRY, "domain_id": domain}  # type: ignore[misc]
        peer = ServerThread(domain, period=0.5).start()
        try:
            yield
        finally:
            peer.stop()

    def make_clock(self) -> Clock:
        return WallClock()  # DDS and the peer run in real time
