"""Missions whose performers run in another ``plansys-bridge performers`` process.

Shared by the DDS hub tests and the terminal's DDS tests: one flat-navigation
mission on a random loopback DDS domain, and the performers process that serves it.
"""

from __future__ import annotations

import contextlib
import os
import random
import selectors
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

PDDL = Path(__file__).resolve().parents[1] / "configs" / "pddl" / "flat_navigation.pddl"

MISSION = """\
name: {name}
domain: {domain}
knowledge:
  instances: {{r1: robot, r2: robot, hall: room, kitchen: room, bedroom: room}}
  predicates:
    - (robot_at r1 hall)
    - (robot_at r2 hall)
    - (connected hall kitchen)
    - (connected hall bedroom)
    - (connected kitchen bedroom)
  functions:
    - (= (travel_time hall kitchen) 1)
    - (= (travel_time hall bedroom) 1)
    - (= (travel_time kitchen bedroom) 1)
goal: {goal}
performers:
{performers}
transport: {{kind: dds, domain_id: {domain_id}, peer_timeout: {peer_timeout}}}
clock: {{kind: wall, time_scale: 0.2}}
timeout: 60
"""

TWO_ROBOTS = """\
  - {kind: simulated, name: r1_base, actions: {move: [r1]}, default_duration: 1.0,
     feedback_period: 0.5}
  - {kind: simulated, name: r2_base, actions: {move: [r2]}, default_duration: 1.0,
     feedback_period: 0.5}"""
"""r1_base moves r1 and r2_base moves r2: the performers another process serves."""


def random_domain_id() -> int:
    """A DDS domain of its own, so parallel runs on one machine do not meet."""
    return random.SystemRandom().randint(1, 232)


def write_mission(
    tmp_path: Path,
    *,
    name: str = "dds_flat",
    performers: str = TWO_ROBOTS,
    goal: str = "(and (visited r1 kitchen) (visited r2 bedroom) (visited r1 bedroom))",
    domain_id: int | None = None,
    peer_timeout: float = 15.0,
) -> Path:
    path = tmp_path / f"{name}.yaml"
    path.write_text(
        MISSION.format(
            name=name,
            domain=PDDL,
            goal=goal,
            performers=performers,
            domain_id=random_domain_id() if domain_id is None else domain_id,
            peer_timeout=peer_timeout,
        ),
        encoding="utf-8",
    )
    return path


def read_line(proc: subprocess.Popen[str], timeout: float) -> str:
    """The next stdout line of ``proc``; fails the test instead of hanging."""
    assert proc.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        if not sel.select(timeout):
            pytest.fail(f"no output from the performers process within {timeout} s")
    return proc.stdout.readline()


@contextlib.contextmanager
def performers_in_subprocess(
    mission: Path, duration: float = 80
) -> Iterator[subprocess.Popen[str]]:
    """``plansys-bridge performers MISSION`` in a subprocess, killed if still running."""
    command = [sys.executable, "-m", "plansys_bridge", "performers", str(mission)]
    proc = subprocess.Popen(
        [*command, "--duration", str(duration)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ | {"PYTHONUNBUFFERED": "1"},
    )
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.communicate(timeout=10)
