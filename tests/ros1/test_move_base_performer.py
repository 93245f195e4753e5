"""The ros1_move_base performer against rospy's actionlib move_base double and roscore."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
from plansys_bridge_adapters.ros1.performer import MoveBasePerformer

from plansys_bridge.clock import WallClock
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import PerformerState
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.registry import load_performer_kind
from plansys_bridge.ros1.roscore import Roscore, free_port

REPO = Path(__file__).resolve().parents[2]
LOCATIONS = {
    "kitchen": {"x": 0.0, "y": 0.0, "yaw": 0.0},
    "livingroom": {"x": 2.0, "y": 1.0, "yaw": 1.57},
    "bedroom": {"x": -2.0, "y": 40.0},
    "bathroom": {"x": -60.0, "y": 0.0},  # the double aborts: "no path to goal"
}


def knowledge() -> ProblemExpert:
    domain = parse_domain_files([REPO / "configs" / "pddl" / "flat_navigation.pddl"])
    expert = ProblemExpert(domain)
    expert.add_instance("tiago", "robot")
    for room in LOCATIONS:
        expert.add_instance(room, "room")
    return expert


def performer(hub: Hub, uri: str, ns: str, **extra: Any) -> MoveBasePerformer:
    config: dict[str, Any] = {
        "kind": "ros1_move_base",
        "name": "tiago_nav",
        "actions": {"move": ["tiago"]},
        "master_uri": uri,
        "action_ns": ns,
        "locations": LOCATIONS,
    }
    config.update(extra)
    context = PerformerContext(hub=hub, clock=hub.clock, knowledge=knowledge())
    [made] = MoveBasePerformer.from_config(config, context, key="performers[0]")
    assert isinstance(made, MoveBasePerformer)
    return made


def wall_hub() -> Hub:
    return Hub(InProcessTransport(), WallClock())


@contextlib.asynccontextmanager
async def started_performer(uri: str, ns: str) -> AsyncIterator[tuple[Hub, MoveBasePerformer]]:
    """A wall-clock hub and a started performer on it; both stop after the block."""
    hub = wall_hub()
    await hub.start()
    try:
        async with performer(hub, uri, ns) as p:
            assert isinstance(p, MoveBasePerformer)
            yield hub, p
    finally:
        await hub.close()


@contextlib.asynccontextmanager
async def ready_performer(uri: str, ns: str) -> AsyncIterator[tuple[Hub, MoveBasePerformer]]:
    """As :func:`started_performer`, once the performer says READY (move_base found)."""
    async with started_performer(uri, ns) as (hub, p):
        async with asyncio.timeout(20):
            while p.state is not PerformerState.READY:
                await asyncio.sleep(0.05)
        yield hub, p


def test_entry_point_names_the_performer() -> None:
    assert load_performer_kind("ros1_move_base") is MoveBasePerformer


def test_move_succeeds_with_feedback(roscore: Roscore, start_peer: Any) -> None:
    double = start_peer("move_base_double.py", "/tiago_mb", "10")

    async def main() -> None:
        async with ready_performer(roscore.uri, "/tiago_mb") as (hub, _p):
            feedback: list[tuple[float, str]] = []
            client = ActionClient(hub, "move", ("tiago", "kitchen", "livingroom"))
            outcome = await client.run(lambda c, s: feedback.append((c, s)))
            assert outcome.success, outcome
            assert outcome.status.startswith("reached livingroom")
            assert feedback and feedback[-1][1].endswith("m to livingroom")
            completions = [c for c, _ in feedback]
            assert completions == sorted(completions) and completions[-1] > 0.9

    asyncio.run(main())
    assert double.expect("succeeded") == "succeeded 2.00 1.00"


def test_abort_fails_with_the_status_text(roscore: Roscore, start_peer: Any) -> None:
    start_peer("move_base_double.py", "/tiago_mb2", "10")

    async def main() -> None:
        async with ready_performer(roscore.uri, "/tiago_mb2") as (hub, _p):
            outcome = await ActionClient(hub, "move", ("tiago", "kitchen", "bathroom")).run()
            assert not outcome.success
            assert outcome.status == "move_base ABORTED going to bathroom: no path to goal"

    asyncio.run(main())


def test_halt_cancels_the_goal(roscore: Roscore, start_peer: Any) -> None:
    double = start_peer("move_base_double.py", "/tiago_mb3", "1")

    async def main() -> None:
        async with ready_performer(roscore.uri, "/tiago_mb3") as (hub, p):
            client = ActionClient(hub, "move", ("tiago", "kitchen", "bedroom"))
            task = asyncio.ensure_future(client.run())
            while p.completion <= 0.0:
                await asyncio.sleep(0.05)
            client.cancel()
            outcome = await task
            assert outcome.cancelled and not outcome.success
            async with asyncio.timeout(10):
                while p.busy:
                    await asyncio.sleep(0.05)

    asyncio.run(main())
    assert double.expect("preempted") == "preempted"


def test_unreachable_master_means_not_ready_and_no_bid(
    ros1_available: None, caplog: pytest.LogCaptureFixture
) -> None:
    uri = f"http://127.0.0.1:{free_port()}"

    async def main() -> None:
        async with started_performer(uri, "/move_base") as (hub, p):
            p.node.watch_period = 0.1  # type: ignore[union-attr]
            await asyncio.sleep(1.0)
            assert p.state is PerformerState.NOT_READY
            policy = AuctionPolicy(give_up_after=1.5)
            outcome = await ActionClient(
                hub, "move", ("tiago", "kitchen", "livingroom"), policy=policy
            ).run()
            assert outcome.gave_up

    with caplog.at_level(logging.ERROR):
        asyncio.run(main())
    lines = [r.getMessage() for r in caplog.records if "does not answer" in r.getMessage()]
    assert len(lines) == 1 and uri in lines[0]


def test_destination_without_location_is_a_load_error() -> None:
    places = {k: v for k, v in LOCATIONS.items() if k != "bedroom"}
    with pytest.raises(ConfigError) as info:
        performer(wall_hub(), "http://127.0.0.1:11311", "/move_base", locations=places)
    assert str(info.value).startswith("performers[0].locations: no location for 'bedroom'")


@pytest.mark.parametrize(
    ("extra", "key"),
    [
        ({"target_arg": 5}, "performers[0].target_arg"),
        ({"target_arg": "last"}, "performers[0].target_arg"),
        ({"master_uri": "localhost:11311"}, "performers[0].master_uri"),
        ({"locations": {"hall": {"x": 1.0}}}, "performers[0].locations.hall.y"),
        ({"locations": {"hall": {"x": 1.0, "y": 2.0, "z": 3.0}}}, "performers[0].locations.hall.z"),
        ({"locations": []}, "performers[0].locations"),
        ({"frame": "map"}, "performers[0].frame"),
    ],
)
def test_bad_settings_name_their_key(extra: dict[str, Any], key: str) -> None:
    with pytest.raises(ConfigError) as info:
        performer(wall_hub(), "http://127.0.0.1:11311", "/move_base", **extra)
    assert str(info.value).startswith(key + ":"), str(info.value)
