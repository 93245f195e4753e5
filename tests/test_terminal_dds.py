"""``check actors`` and ``run`` in the terminal over a DDS hub, with performers in
another process (``plansys-bridge performers``) on the same domain (loopback)."""

from __future__ import annotations

import argparse
import io
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from dds_missions import performers_in_subprocess, random_domain_id, read_line, write_mission

from plansys_bridge.cli import terminal_cmd

pytestmark = pytest.mark.timeout(120)

LOCAL = """\
  - {kind: simulated, name: r3_local, actions: {move: [r1]}, default_duration: 1.0}"""

GOAL = "(and (visited r1 kitchen) (visited r2 bedroom))"


@pytest.fixture
def domain_id() -> int:
    return random_domain_id()


@pytest.fixture
def remote_performers(tmp_path: Path, domain_id: int) -> Iterator[Path]:
    """``plansys-bridge performers`` serving r1_base and r2_base in a subprocess."""
    mission = write_mission(tmp_path, name="fleet", goal=GOAL, domain_id=domain_id, peer_timeout=20)
    with performers_in_subprocess(mission, duration=90) as proc:
        ready = read_line(proc, timeout=30)
        assert ready.startswith("performers ready: r1_base, r2_base"), ready
        yield mission


def _args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    terminal_cmd.register(parser.add_subparsers())
    return parser.parse_args(["terminal", *argv])


def _actors(text: str) -> dict[str, str]:
    """``check actors`` output -> performer name -> the rest of its line."""
    return dict(re.findall(r"^\t\[(\w+)\] (.*)$", text, flags=re.MULTILINE))


def test_check_actors_hears_performers_of_other_processes(
    tmp_path: Path, remote_performers: Path, domain_id: int
) -> None:
    mine = write_mission(
        tmp_path, name="operator", performers=LOCAL, goal=GOAL, domain_id=domain_id, peer_timeout=20
    )
    # each check listens two seconds on a fresh DDS participant; a loaded machine may
    # discover the other process later than that, so a few checks are allowed
    for _attempt in range(3):
        out = io.StringIO()
        code = terminal_cmd.run(_args("--mission", str(mine)), io.StringIO("check actors\n"), out)
        text = out.getvalue()
        assert code == 0, text
        if text.startswith("Actors: 3\n"):
            break
    assert text.startswith("Actors: 3\n"), text
    actors = _actors(text)
    assert set(actors) == {"r1_base", "r2_base", "r3_local"}
    assert re.fullmatch(r"move \[r2\]\tREADY\tlast seen [01]\.\d s ago", actors["r2_base"])
    assert actors["r1_base"].startswith("move [r1]\tREADY\t")


def test_terminal_runs_plans_on_performers_of_another_process(remote_performers: Path) -> None:
    out = io.StringIO()
    # run first: it waits for the other process's heartbeats, so the check after it
    # hears a process known to be up
    commands = "run\ncheck actors\nget problem predicates\n"
    code = terminal_cmd.run(
        _args("--mission", str(remote_performers), "--no-performers"), io.StringIO(commands), out
    )
    text = out.getvalue()
    assert code == 0, text
    # only the other process's performers (none was started here)
    assert set(_actors(text)) <= {"r1_base", "r2_base"}
    assert "succeeded\n" in text
    assert "ASSIGNED  (move r1 hall kitchen) -> r1_base (1 bid)" in text
    assert "ASSIGNED  (move r2 hall bedroom) -> r2_base (1 bid)" in text
    assert "(visited r1 kitchen)" in text and "(visited r2 bedroom)" in text
