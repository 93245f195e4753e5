"""Missions choose the solver and its options by name (``planner:``)."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest
import yaml

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission, make_planner

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _mission(tmp_path: Path, planner: Any) -> Path:
    data = yaml.safe_load((CONFIGS / "demo_cooking.yaml").read_text())
    data["domain"] = str(CONFIGS / data["domain"])
    data["clock"] = {"kind": "virtual"}
    data["planner"] = planner
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_named_solver_and_options_plan_the_mission(tmp_path: Path) -> None:
    planner = {"solver": "kairos", "timeout": 20, "options": {"kairos": {"threads": 1}}}
    mission = load_mission(_mission(tmp_path, planner))
    built = make_planner(mission)
    assert [s.name for s in built.solvers] == ["kairos"]
    assert built.solvers[0].options == {"threads": 1}
    assert built.timeout == 20.0
    report = run_mission(mission, out=None)
    assert report.success, report.message
    assert report.result is not None and report.result.plans


@pytest.mark.skipif(shutil.which("popf") is not None, reason="popf is installed here")
def test_the_named_solver_is_the_one_used(tmp_path: Path) -> None:
    """Only popf (not installed here): the mission does not quietly plan with another."""
    report = run_mission(load_mission(_mission(tmp_path, {"solver": "popf"})), out=None)
    assert not report.success
    assert report.status == "no plan"
    assert "popf" in report.message


@pytest.mark.parametrize(
    ("planner", "key", "text"),
    [
        ({"solver": "kairoz"}, "planner.solver", "unknown solver 'kairoz'"),
        ({"solver": ["kairos", "nope"]}, "planner.solver", "unknown solver 'nope'"),
        (
            {"solver": "kairos", "options": {"kairos": {"thread": 1}}},
            "planner.options.kairos.thread",
            "unknown key (allowed: ",
        ),
        (
            {"solver": "kairos", "options": {"kairos": {"threads": "two"}}},
            "planner.options.kairos.threads",
            "valid integer, got 'two'",
        ),
        (
            {"solver": "kairos", "options": {"nope": 1}},
            "planner.options.nope",
            "accepts this option",
        ),
        ({"timeout": 0}, "planner.timeout", "greater than 0"),
        ({"timeout": float("inf")}, "planner.timeout", "finite"),
        ({"solvers": "kairos"}, "planner.solvers", "unknown key"),
    ],
)
def test_planner_errors_name_the_key(tmp_path: Path, planner: Any, key: str, text: str) -> None:
    path = _mission(tmp_path, planner)
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert err.value.key == key, str(err.value)
    assert err.value.file == str(path)
    assert text in str(err.value)
