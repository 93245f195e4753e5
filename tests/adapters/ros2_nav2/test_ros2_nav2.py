"""The ``ros2_nav2`` performer against an independent NavigateToPose action server
(tests/nav2_peer.py: plain Cyclone DDS, types from the upstream texts)."""

import asyncio
import random
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from nav2_peer import RawNavigateToPoseServer
from plansys_bridge_adapters.ros2_nav2.performer import Nav2Performer
from ros2_upstream import CANCELED, SUCCEEDED

from plansys_bridge.clock import WallClock
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import PerformerContext

pytestmark = [pytest.mark.timeout(90), pytest.mark.usefixtures("no_leaks")]

DOMAIN = Path(__file__).resolve().parents[3] / "configs" / "pddl" / "flat_navigation.pddl"


LOCATIONS = {
    "hall": {"x": 0.0, "y": 0.0},
    "kitchen": {"x": 4.0, "y": 1.0, "yaw": 1.57},
    "bedroom": {"x": 9.0, "y": 0.0},
    "garden": {"x": 30.0, "y": 0.0},
}


def _entry(domain: int, **extra: Any) -> dict[str, Any]:
    return {
        "kind": "ros2_nav2",
        "name": "tb3",
        "actions": {"move": ["r1"]},
        "frame_id": "map",
        "locations": LOCATIONS,
        "domain_id": domain,
        **extra,
    }


def _knowledge() -> ProblemExpert:
    k = ProblemExpert(parse_domain_files([DOMAIN]))
    k.add_instance("r1", "robot")
    for room in LOCATIONS:
        k.add_instance(room, "room")
    return k


def run_moves(script: Any) -> tuple[list[ActionExecution], RawNavigateToPoseServer]:
    """Start the peer and the performer, run ``script(hub, send)``, return the messages."""

    async def main() -> tuple[list[ActionExecution], RawNavigateToPoseServer]:
        domain = random.SystemRandom().randint(1, 232)
        hub = Hub(clock=WallClock())
        await hub.start()
        seen: list[ActionExecution] = []
        hub.subscribe(Topics.ACTIONS_HUB, lambda m: seen.append(m))
        context = PerformerContext(hub, hub.clock, knowledge=_knowledge())
        (performer,) = Nav2Performer.from_config(_entry(domain), context)
        await performer.start()  # first: its node opens the domain on the loopback config
        server = RawNavigateToPoseServer(domain)
        server.start()
        try:
            async with asyncio.timeout(20):
                while not performer.ready:
                    await asyncio.sleep(0.02)

            async def send(kind: ExecutionType, args: tuple[str, ...], rid: str) -> None:
                node = "" if kind is ExecutionType.REQUEST else "tb3"
                hub.publish(
                    Topics.ACTIONS_HUB, ActionExecution(kind, node, "move", args, request_id=rid)
                )
                await asyncio.sleep(0.01)

            await script(seen, send)
        finally:
            await performer.stop()
            await server.close()
            await hub.close()
        return seen, server

    return asyncio.run(main())


async def _finish(seen: list[ActionExecution], rid: str) -> ActionExecution:
    async with asyncio.timeout(15):
        while True:
            for m in seen:
                if m.type is ExecutionType.FINISH and m.request_id == rid:
                    return m
            await asyncio.sleep(0.01)


def test_goal_succeeds_with_feedback_from_distance_remaining() -> None:
    async def script(seen: list[ActionExecution], send: Any) -> None:
        await send(ExecutionType.REQUEST, ("r1", "hall", "kitchen"), "a")
        await send(ExecutionType.CONFIRM, ("r1", "hall", "kitchen"), "a")
        finish = await _finish(seen, "a")
        assert finish.success, finish.status
        assert finish.status == "reached kitchen"

    seen, server = run_moves(script)
    ((goal_x, goal),) = [(g["x"], g) for g in server.goals.values()]
    assert goal_x == 4.0 and goal["status"] == SUCCEEDED
    feedback = [m.completion for m in seen if m.type is ExecutionType.FEEDBACK]
    # 3, 2, 1, 0 m left of at most 3 m: 0, 1/3, 2/3, 1 (a loaded machine may merge or
    # repeat a sample, never invent one or go backwards)
    steps = [0.0, 1 / 3, 2 / 3, 1.0]
    assert feedback == sorted(feedback), feedback
    assert all(min(abs(f - s) for s in steps) < 1e-6 for f in feedback), feedback
    assert any(abs(f - 1 / 3) < 1e-6 or abs(f - 2 / 3) < 1e-6 for f in feedback), feedback


def test_aborted_goal_fails_with_the_result_code() -> None:
    async def script(seen: list[ActionExecution], send: Any) -> None:
        await send(ExecutionType.REQUEST, ("r1", "hall", "bedroom"), "b")
        await send(ExecutionType.CONFIRM, ("r1", "hall", "bedroom"), "b")
        finish = await _finish(seen, "b")
        assert not finish.success
        assert "ABORTED" in finish.status and "204" in finish.status
        assert "no valid path" in finish.status

    run_moves(script)


def test_halt_cancels_the_nav2_goal() -> None:
    async def script(seen: list[ActionExecution], send: Any) -> None:
        await send(ExecutionType.REQUEST, ("r1", "hall", "garden"), "c")
        await send(ExecutionType.CONFIRM, ("r1", "hall", "garden"), "c")
        async with asyncio.timeout(10):
            while not any(m.type is ExecutionType.FEEDBACK for m in seen):
                await asyncio.sleep(0.01)
        await send(ExecutionType.CANCEL, ("r1", "hall", "garden"), "c")
        await asyncio.sleep(0.5)

    seen, server = run_moves(script)
    (gid,) = server.goals
    assert server.cancels == [gid]
    assert server.goals[gid]["status"] == CANCELED
    assert not any(m.type is ExecutionType.FINISH for m in seen)


def test_a_destination_without_location_is_a_load_error() -> None:
    hub = Hub(clock=WallClock())
    context = PerformerContext(hub, hub.clock, knowledge=_knowledge())
    entry = _entry(5, locations={"hall": {"x": 0, "y": 0}})
    with pytest.raises(ConfigError) as err:
        Nav2Performer.from_config(entry, context, key="performers[0]")
    assert err.value.key == "performers[0].locations"
    assert "no location for 'bedroom'" in str(err.value)
