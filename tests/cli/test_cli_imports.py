"""The command line starts without loading what it does not need: ``--help`` of the
tool and of every subcommand imports none of the heavy libraries, and each command
loads only the libraries of its own work (checked in a fresh interpreter)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from plansys_bridge.cli import SUBCOMMANDS

HEAVY = (
    "asyncio",
    "cantools",
    "can",
    "cyclonedds",
    "kairos",
    "lark",
    "networkx",
    "py_trees",
    "pydantic",
    "pymavlink",
    "rosbags",
    "yaml",
)

PROBE = """
import contextlib, io, json, sys
from plansys_bridge.cli import main
argv = json.loads(sys.argv[1])
with contextlib.redirect_stdout(io.StringIO()) as out, contextlib.suppress(SystemExit):
    main(argv)
heavy = json.loads(sys.argv[2])
print(json.dumps({"loaded": sorted(h for h in heavy if h in sys.modules), "out": out.getvalue()}))
"""


def _loaded(argv: list[str]) -> tuple[list[str], str]:
    done = subprocess.run(
        [sys.executable, "-c", PROBE, json.dumps(argv), json.dumps(HEAVY)],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    data = json.loads(done.stdout)
    return data["loaded"], data["out"]


@pytest.mark.parametrize("argv", [["--help"], *([name, "--help"] for name in SUBCOMMANDS)])
def test_help_loads_no_heavy_library(argv: list[str]) -> None:
    loaded, out = _loaded(argv)
    assert "usage: plansys-bridge" in out
    assert loaded == []


def test_validate_loads_the_parser_but_no_planner_executor_or_transport(tmp_path: Path) -> None:
    domain = tmp_path / "d.pddl"
    domain.write_text("(define (domain d) (:predicates (p)))", encoding="utf-8")
    loaded, out = _loaded(["validate", str(domain)])
    assert "domain d:" in out
    assert "lark" in loaded
    assert not {"cyclonedds", "py_trees", "networkx", "pymavlink", "rosbags", "can"} & set(loaded)
