"""``plansys-bridge plan``: output format, exit statuses, messages."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest
import tasks
from pddl_corpus import CORPUS

from plansys_bridge.cli import plan_cmd
from plansys_bridge.errors import PddlError
from plansys_bridge.planning.plan import parse_plan

COOKING = (CORPUS or Path("/nonexistent")) / "plansys2_cooking_experiment" / "pddl"


def run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="plansys-bridge")
    plan_cmd.register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["plan", *argv])
    code: int = args.func(args)
    return code


@pytest.fixture()
def fleet(tmp_path: Path) -> tuple[str, str]:
    (tmp_path / "domain.pddl").write_text(tasks.TEMPORAL_DOMAIN)
    (tmp_path / "problem.pddl").write_text(tasks.TEMPORAL_PROBLEM)
    return str(tmp_path / "domain.pddl"), str(tmp_path / "problem.pddl")


def test_prints_plan_and_makespan(
    fleet: tuple[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert run([*fleet]) == 0
    out = capsys.readouterr().out
    plan = parse_plan(out)
    assert len(plan) == 4
    assert "; makespan 15.000" in out
    assert "; solver kairos" in out
    assert "; plan valid" in out


def test_cooking_problem_with_trailing_commands(capsys: pytest.CaptureFixture[str]) -> None:
    if not COOKING.is_dir():
        pytest.skip("PlanSys2 corpus not found")
    code = run([str(COOKING / "cooking_domain.pddl"), str(COOKING / "cooking_problem_1.pddl")])
    assert code == 0
    assert "(cook_cake r2d2 cooking_zone flour eggs sugar cake)" in capsys.readouterr().out


def test_output_file_and_reschedule(
    fleet: tuple[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_file = tmp_path / "plan.txt"
    assert run([*fleet, "-o", str(out_file), "--reschedule", "--solver", "kairos"]) == 0
    out = capsys.readouterr().out
    assert f"; plan written to {out_file}" in out
    assert "; rescheduled: makespan before 15.000, after 15.000" in out
    assert len(parse_plan(out_file.read_text())) == 4


def test_unsolvable_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "d.pddl").write_text(tasks.CLASSICAL_DOMAIN)
    (tmp_path / "p.pddl").write_text(tasks.CLASSICAL_UNSOLVABLE)
    assert run([str(tmp_path / "d.pddl"), str(tmp_path / "p.pddl")]) == 1
    err = capsys.readouterr().err
    assert "error: no plan (unsolvable) from kairos" in err


def test_unsupported_exits_1(fleet: tuple[str, str], capsys: pytest.CaptureFixture[str]) -> None:
    assert run([*fleet, "--solver", "fast-downward"]) == 1
    assert "does not support :durative-actions" in capsys.readouterr().err


def test_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert run([str(tmp_path / "only_one.pddl")]) == 2
    assert "at least one DOMAIN" in capsys.readouterr().err
    (tmp_path / "d.pddl").write_text(tasks.CLASSICAL_DOMAIN)
    assert run([str(tmp_path / "d.pddl"), str(tmp_path / "missing.pddl")]) == 2
    assert "cannot read problem file" in capsys.readouterr().err
    (tmp_path / "p.pddl").write_text(tasks.CLASSICAL_PROBLEM.replace("(at r1 a)", "(at r1 zz)"))
    with pytest.raises(PddlError, match=r"p\.pddl:4"):
        run([str(tmp_path / "d.pddl"), str(tmp_path / "p.pddl")])
    (tmp_path / "p.pddl").write_text(tasks.CLASSICAL_PROBLEM)
    assert run([str(tmp_path / "d.pddl"), str(tmp_path / "p.pddl"), "--timeout", "-1"]) == 2
    assert "timeout must be positive" in capsys.readouterr().err


def test_list_solvers(capsys: pytest.CaptureFixture[str]) -> None:
    assert run(["--list-solvers"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("kairos")
    assert "available" in out and "lpg" in out
