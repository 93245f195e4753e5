"""``plansys-bridge validate``: summaries, located errors, exit codes."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest
from pddl_corpus import CORPUS

from plansys_bridge.cli import validate_cmd

pytestmark = pytest.mark.skipif(CORPUS is None, reason="PlanSys2 PDDL corpus not found")


def _run(*argv: str | Path) -> int:
    parser = argparse.ArgumentParser(prog="plansys-bridge")
    validate_cmd.register(parser.add_subparsers())
    args = parser.parse_args(["validate", *map(str, argv)])
    code: int = args.func(args)
    return code


@pytest.fixture
def pe() -> Path:
    assert CORPUS is not None
    return CORPUS / "ros2_planning_system/plansys2_problem_expert/test/pddl"


def test_domain_and_problem_summary(pe: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _run(pe / "domain_charging.pddl", "--problem", pe / "problem_charging.pddl") == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [
        "domain charging: 2 types, 0 constants, 4 predicates, 4 functions, "
        "3 actions (3 durative), 0 derived predicates",
        "problem charging-problem: 6 objects, 10 facts, 23 numeric values, "
        "4 goal conditions, metric minimize",
    ]


def test_several_domain_files_are_merged(capsys: pytest.CaptureFixture[str]) -> None:
    assert CORPUS is not None
    base = CORPUS / "ros2_planning_system_examples/plansys2_multidomain_example"
    assert _run(base / "pddl_1/domain_1.pddl", base / "pddl_2/domain_2.pddl") == 0
    out = capsys.readouterr().out
    assert out.startswith("domain multidomain1_multidomain2: 3 types,")
    assert "5 actions (5 durative)" in out


def test_bad_problem_exits_2_with_location(pe: Path, capsys: pytest.CaptureFixture[str]) -> None:
    problem = pe / "problem_unexpected_syntax.pddl"
    assert _run(pe / "domain_simple.pddl", "--problem", problem) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {problem}:16:6: predicate 'is_teleporter_destination'")
    assert "(is_teleporter_destination kitchen bedroom)" in err and "^" in err


def test_bad_domain_and_missing_file(pe: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert CORPUS is not None
    broken = CORPUS / "ros2_planning_system/plansys2_domain_expert/test/pddl/domain_2_error.pddl"
    assert _run(broken) == 2
    assert f"{broken}:37:1: unexpected '('" in capsys.readouterr().err
    assert _run(pe / "domain_simple.pddl", "--problem", pe / "missing.pddl") == 2
    assert "cannot read" in capsys.readouterr().err


def test_plan_validation(pe: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = (pe / "problem_charging.pddl").read_text(encoding="utf-8")
    for wp in ("wp2", "wp3", "wp4"):
        text = text.replace(f"(patrolled {wp})", "")
    problem = tmp_path / "problem.pddl"
    problem.write_text(text, encoding="utf-8")
    good = tmp_path / "good.plan"
    good.write_text(
        "0.000: (move r2d2 wp_control wp1) [15.000]\n15.001: (patrol r2d2 wp1) [5.000]\n"
    )
    bad = tmp_path / "bad.plan"
    bad.write_text("0.000: (patrol r2d2 wp1) [5.000]\n")
    domain = pe / "domain_charging.pddl"
    assert _run(domain, "--problem", problem, "--plan", good) == 0
    assert "valid" in capsys.readouterr().out
    assert _run(domain, "--problem", problem, "--plan", bad) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"error: {bad}: ") and "robot_at r2d2 wp1" in err
    assert _run(domain, "--plan", good) == 2
