"""PlanSys2 action performers written from upstream (tests/interop/plansys2_peer.py) join
the project's auctions over DDS: alone, mixed with project performers, and through
REJECT and CANCEL."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import random
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from plansys2_peer import ActionExecution_, PlanSys2Performer, loopback_domain

from plansys_bridge.clock import WallClock
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.dds import DdsTransport
from plansys_bridge.hub.hub import Hub

pytestmark = pytest.mark.timeout(120)

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "dds_flat.yaml"


def mission_copy(tmp_path: Path, domain_id: int, name: str = "mission.yaml") -> Path:
    """configs/dds_flat.yaml on another domain id (runs on one machine must not meet)."""
    text = CONFIG.read_text(encoding="utf-8")
    text = text.replace("domain_id: 42", f"domain_id: {domain_id}")
    text = text.replace("domain: pddl/", f"domain: {CONFIG.parent / 'pddl'}/")
    assert f"domain_id: {domain_id}" in text
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def plansys_bridge(*args: str) -> list[str]:
    return [sys.executable, "-m", "plansys_bridge", *args]


@contextlib.contextmanager
def peers(domain_id: int, *specs: tuple[str, str]) -> Iterator[list[PlanSys2Performer]]:
    """PlanSys2 performers ``(node name, specialised robot)`` serving ``move``."""
    domain = loopback_domain(domain_id)
    nodes = [PlanSys2Performer(domain_id, name, "move", (robot,)) for name, robot in specs]
    try:
        for node in nodes:
            node.start()
        yield nodes
    finally:
        for node in nodes:
            node.stop()
        del domain


@contextlib.contextmanager
def noise(domain_id: int) -> Iterator[None]:
    """A foreign node writing a REQUEST for an action the domain lacks every 0.2 s."""
    stop = threading.Event()
    participant = DomainParticipant(domain_id)
    writer = DataWriter(participant, Topic(participant, "rt/actions_hub", ActionExecution_))

    def spam() -> None:
        while not stop.wait(0.2):
            writer.write(ActionExecution_(type=1, action="fly", arguments=["r1", "hall"]))

    thread = threading.Thread(target=spam, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        participant.__del__()


def run_executor(mission: Path, stderr: list[str] | None = None) -> dict[str, Any]:
    """``plansys-bridge run MISSION --no-performers --json``: the executor process alone."""
    proc = subprocess.run(
        plansys_bridge("run", str(mission), "--no-performers", "--json"),
        capture_output=True,
        text=True,
        timeout=100,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    if stderr is not None:
        stderr.append(proc.stderr)
    report: dict[str, Any] = json.loads(proc.stdout[proc.stdout.index("{") :])
    return report


def moves_of(report: dict[str, Any], robot: str) -> list[tuple[str, str]]:
    return [
        (r["action"], r["performer"])
        for r in report["records"]
        if r["action"].startswith(f"(move {robot} ")
    ]


def test_two_plansys2_performers_do_every_action_of_the_dds_flat_mission(
    tmp_path: Path,
) -> None:
    domain_id = random.SystemRandom().randint(1, 232)
    mission = mission_copy(tmp_path, domain_id)
    stderr: list[str] = []
    with peers(domain_id, ("r1_base", "r1"), ("r2_base", "r2")) as (r1, r2), noise(domain_id):
        report = run_executor(mission, stderr)
    assert report["success"], report
    # A node writing nonsense all along was dropped, one line per sample, and changed nothing.
    assert "rt/actions_hub: dropped a sample from writer " in stderr[0]
    assert "unknown action 'fly'" in stderr[0]
    assert report["failures"] == 0
    r1_moves, r2_moves = moves_of(report, "r1"), moves_of(report, "r2")
    assert r1_moves and r2_moves
    assert len(r1_moves) + len(r2_moves) == len(report["records"])
    assert {p for _, p in r1_moves} == {"r1_base"}
    assert {p for _, p in r2_moves} == {"r2_base"}
    # What the executor recorded is what the PlanSys2 nodes did, action for action.
    assert sorted(f"(move {' '.join(a)})" for a in r1.finished) == sorted(a for a, _ in r1_moves)
    assert sorted(f"(move {' '.join(a)})" for a in r2.finished) == sorted(a for a, _ in r2_moves)
    assert not r1.cancelled and not r2.cancelled


def test_plansys2_and_project_performers_share_a_mission(tmp_path: Path) -> None:
    """r1 by the project's simulated performer in its own process, r2 by a PlanSys2 node."""
    domain_id = random.SystemRandom().randint(1, 232)
    mission = mission_copy(tmp_path, domain_id)
    only_r1 = mission.read_text(encoding="utf-8").replace(
        "  - {kind: simulated, name: r2_base, actions: {move: [r2]}, default_duration: 5}\n", ""
    )
    assert "r2_base" not in only_r1
    r1_file = tmp_path / "r1_only.yaml"
    r1_file.write_text(only_r1, encoding="utf-8")
    performers = subprocess.Popen(
        plansys_bridge("performers", str(r1_file)),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        with peers(domain_id, ("r2_base", "r2")) as (r2,):
            report = run_executor(mission)
    finally:
        performers.terminate()
        _, err = performers.communicate(timeout=30)
    assert report["success"], (report, err)
    assert {p for _, p in moves_of(report, "r1")} == {"r1_base"}
    assert {p for _, p in moves_of(report, "r2")} == {"r2_base"}
    assert len(r2.finished) == len(moves_of(report, "r2")) >= 1


async def _until(predicate: Any, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached in time"
        await asyncio.sleep(0.02)


def test_plansys2_performers_honour_reject_and_cancel() -> None:
    """Two PlanSys2 nodes answer one REQUEST: the first is confirmed, the other gets a
    REJECT and answers the next REQUEST again; a CANCEL stops the confirmed node
    without a FINISH."""
    domain_id = random.SystemRandom().randint(1, 232)

    async def main() -> None:
        hub = Hub(DdsTransport(domain_id), WallClock())
        await hub.start()  # opens the domain (loopback) the PlanSys2 nodes join
        a = PlanSys2Performer(domain_id, "mover_a", "move", ("",), steps=200)
        b = PlanSys2Performer(domain_id, "mover_b", "move", ("",), steps=200)
        a.start()
        b.start()
        try:
            # Each node's actions_hub reader has matched the three writers (both nodes' and
            # the hub's plain one).
            await _until(lambda: min(a.matched_writers(), b.matched_writers()) >= 3)
            first = ActionClient(hub, "move", ["r1", "hall", "kitchen"])
            task = asyncio.ensure_future(first.run())
            await _until(lambda: a.active or b.active)
            winner, loser = (a, b) if a.active else (b, a)
            assert first.performer == winner.node_name
            await _until(lambda: loser.rejects == 1)
            assert not loser.committed
            # The rejected node is free: it takes the next action.
            second = ActionClient(hub, "move", ["r2", "hall", "bedroom"])
            task2 = asyncio.ensure_future(second.run())
            await _until(lambda: loser.active)
            assert second.performer == loser.node_name
            for client in (first, second):
                client.cancel()
            outcomes = await asyncio.wait_for(asyncio.gather(task, task2), 10)
            assert all(o.cancelled and not o.success for o in outcomes)
            await _until(lambda: not a.active and not b.active)
            assert a.cancelled == [("r1", "hall", "kitchen")] or b.cancelled == [
                ("r1", "hall", "kitchen")
            ]
            assert not a.finished and not b.finished
        finally:
            a.stop()
            b.stop()
            await hub.close()

    asyncio.run(main())
