"""A Nav2 goal never outlives its action: stopping the performer (the end of a
mission, an abort) and a real SIGTERM to ``plansys-bridge run`` cancel it on the
independent NavigateToPose server of ``test_ros2_nav2`` (plain Cyclone DDS, types
from the upstream texts)."""

import asyncio
import random
import signal
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

import yaml
from plansys_bridge_adapters.ros2_nav2.performer import Nav2Performer
from ros2_upstream import CANCELED, EXECUTING
from test_ros2_nav2 import DOMAIN, LOCATIONS, RawNavigateToPoseServer, _entry, _knowledge

from plansys_bridge.clock import WallClock
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.ros2.node import Ros2Node

pytestmark = [pytest.mark.timeout(120), pytest.mark.usefixtures("no_leaks")]


async def _until(predicate: Any, timeout: float, what: str) -> None:
    try:
        async with asyncio.timeout(timeout):
            while not predicate():
                await asyncio.sleep(0.02)
    except TimeoutError:
        raise AssertionError(f"timed out waiting for {what}") from None


def test_stopping_the_performer_cancels_the_running_goal() -> None:
    async def main() -> RawNavigateToPoseServer:
        domain = random.SystemRandom().randint(1, 232)
        hub = Hub(clock=WallClock())
        await hub.start()
        context = PerformerContext(hub, hub.clock, knowledge=_knowledge())
        (performer,) = Nav2Performer.from_config(_entry(domain), context)
        await performer.start()
        server = RawNavigateToPoseServer(domain)
        server.start()
        try:
            await _until(lambda: performer.ready, 20, "the performer to see Nav2")
            for kind in (ExecutionType.REQUEST, ExecutionType.CONFIRM):
                node = "" if kind is ExecutionType.REQUEST else "tb3"
                args = ("r1", "hall", "garden")
                hub.publish(Topics.ACTIONS_HUB, ActionExecution(kind, node, "move", args, "g"))
                await asyncio.sleep(0.01)
            await _until(lambda: server.goals, 10, "the goal")
            await performer.stop()
        finally:
            await performer.stop()
            await server.close()
            await hub.close()
        return server

    server = asyncio.run(main())
    (gid,) = server.goals
    assert server.cancels == [gid]
    assert server.goals[gid]["status"] == CANCELED


def _mission(tmp_path: Path, domain: int) -> Path:
    rooms = {room: "room" for room in LOCATIONS}
    data = {
        "name": "nav2_sigterm",
        "domain": str(DOMAIN),
        "knowledge": {
            "instances": {"r1": "robot", **rooms},
            "predicates": ["(robot_at r1 hall)", "(connected hall garden)"],
            "functions": ["(= (travel_time hall garden) 30)"],
        },
        "goal": "(visited r1 garden)",
        "performers": [_entry(domain)],
        "clock": {"kind": "wall"},
    }
    path = tmp_path / "mission.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _cli() -> list[str]:
    script = Path(sys.executable).with_name("plansys-bridge")
    return [str(script)] if script.exists() else [sys.executable, "-m", "plansys_bridge"]


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_to_run_cancels_the_nav2_goal(
    tmp_path: Path, sig: signal.Signals, code: int
) -> None:
    async def main() -> tuple[RawNavigateToPoseServer, int, str]:
        domain = random.SystemRandom().randint(1, 232)
        node = Ros2Node(domain, name="test")  # opens the domain on the loopback config
        await node.start()
        server = RawNavigateToPoseServer(domain)
        server.start()
        proc = await asyncio.create_subprocess_exec(
            *_cli(),
            "run",
            str(_mission(tmp_path, domain)),
            stdin=asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        try:
            running = lambda: any(g["status"] == EXECUTING for g in server.goals.values())  # noqa: E731
            await _until(running, 60, "the mission's goal on the Nav2 server")
            proc.send_signal(sig)
            async with asyncio.timeout(30):
                _out, err = await proc.communicate()
            await asyncio.sleep(0.2)  # the last status and replies
        finally:
            if proc.returncode is None:
                proc.kill()
                await proc.communicate()
            await server.close()
            await node.close()
        return server, proc.returncode or 0, err.decode(errors="replace")

    server, returncode, err = asyncio.run(main())
    assert returncode == code, err
    (gid,) = server.goals
    assert server.cancels == [gid], err
    assert server.goals[gid]["status"] == CANCELED
