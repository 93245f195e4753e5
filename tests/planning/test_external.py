"""Running solvers as programs: the timeout that holds, error messages, output formats.

POPF, OPTIC and TFD are not installed here, so their output formats (as PlanSys2's
plugins read them) are exercised with small shell scripts that print recorded
output; the process handling is exercised with real processes.
"""

from __future__ import annotations

import os
import stat
import time
from pathlib import Path

import pytest
import tasks

from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.solvers.external import OpticSolver, PopfSolver, TfdSolver
from plansys_bridge.planning.solvers.process import run_folder, run_process
from plansys_bridge.planning.validation import validate_plan

POPF_OUTPUT = """\
Number of literals: 7
Constructing lookup tables: [10%] [20%] [30%] [40%] [50%] [60%] [70%] [80%] [90%] [100%]
b (4.000 | 5.000)b (3.000 | 10.001)b (2.000 | 15.002)
;;;; Solution Found
; States evaluated: 10
; Cost: 15.002
; Time 0.00
0.000: (move r1 base k1)  [5.000]
0.000: (move r2 base k2)  [5.000]
5.001: (clean r1 k1)  [10.000]
5.001: (clean r2 k2)  [10.000]
"""


def _script(folder: Path, body: str) -> str:
    path = folder / "solver.sh"
    path.write_text("#!/bin/sh\n" + body)
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return str(path)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"


def test_timeout_stops_the_whole_process_group(tmp_path: Path) -> None:
    started = time.monotonic()
    proc = run_process(
        ["sh", "-c", "sleep 60 & echo $! > child.pid; wait"], cwd=tmp_path, timeout=0.5
    )
    assert proc.timed_out and proc.returncode is None
    assert time.monotonic() - started < 10
    child = int((tmp_path / "child.pid").read_text())
    deadline = time.monotonic() + 5
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(child)
    assert "timeout" in proc.describe()


def test_failure_is_described_with_status_and_stderr(tmp_path: Path) -> None:
    proc = run_process(
        ["sh", "-c", "echo parsing; echo 'bad token' >&2; exit 3"], cwd=tmp_path, timeout=10
    )
    assert proc.returncode == 3 and not proc.timed_out
    assert proc.describe() == "sh exited with status 3; stderr: bad token"


def test_run_folder_is_removed_unless_kept() -> None:
    with run_folder("x") as folder:
        (folder / "f").write_text("")
    assert not folder.exists()
    with run_folder("x", keep=True) as kept:
        pass
    assert kept.is_dir()
    kept.rmdir()


def test_popf_output_is_read(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    (tmp_path / "out.txt").write_text(POPF_OUTPUT)
    exe = _script(tmp_path, f'test -f "$1" && test -f "$2" && cat {tmp_path}/out.txt\n')
    result = PopfSolver({"executable": exe}).solve(domain, problem, timeout=10)
    assert result.status is PlanStatus.SOLVED, str(result)
    assert result.plan is not None and len(result.plan) == 4
    assert validate_plan(domain, problem, result.plan).valid


def test_popf_unsolvable(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    exe = _script(tmp_path, "echo ';; Problem unsolvable!'\n")
    result = PopfSolver({"executable": exe}).solve(domain, problem, timeout=10)
    assert result.status is PlanStatus.UNSOLVABLE


def test_popf_crash_keeps_its_words(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    exe = _script(tmp_path, "echo 'Segmentation fault' >&2\nexit 139\n")
    result = PopfSolver({"executable": exe}).solve(domain, problem, timeout=10)
    assert result.status is PlanStatus.ERROR
    assert "exited with status 139" in result.message
    assert "Segmentation fault" in result.message


def test_hanging_solver_times_out(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    exe = _script(tmp_path, "sleep 60\n")
    started = time.monotonic()
    result = PopfSolver({"executable": exe}).solve(domain, problem, timeout=0.5)
    assert result.status is PlanStatus.TIMEOUT
    assert time.monotonic() - started < 10
    assert "timeout" in result.message


def test_optic_keeps_the_last_plan(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    first = POPF_OUTPUT.replace("5.001: (clean r2 k2)", "20.000: (clean r2 k2)")
    (tmp_path / "out.txt").write_text(first + POPF_OUTPUT)
    exe = _script(tmp_path, f'test "$1" = -N && cat {tmp_path}/out.txt\n')
    result = OpticSolver({"executable": exe}).solve(domain, problem, timeout=10)
    assert result.status is PlanStatus.SOLVED, str(result)
    assert result.plan is not None and result.plan.makespan == pytest.approx(15.001)


def test_tfd_reads_its_best_plan_file(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    plan = "\n".join(POPF_OUTPUT.splitlines()[-4:]) + "\n"
    worse = plan.replace("5.001: (clean r2 k2)", "30.000: (clean r2 k2)")
    exe = _script(
        tmp_path,
        f"printf '%s' '{worse}' > \"$3.1\"\nprintf '%s' '{plan}' > \"$3.2\"\n",
    )
    result = TfdSolver({"executable": exe}).solve(domain, problem, timeout=10)
    assert result.status is PlanStatus.SOLVED, str(result)
    assert result.plan is not None and result.plan.makespan == pytest.approx(15.001)
    assert "2 plan(s)" in result.message


def test_missing_executable_is_unsupported(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    missing = str(tmp_path / "nowhere" / "popf")
    result = PopfSolver({"executable": missing}).solve(domain, problem, timeout=10)
    assert result.status is PlanStatus.UNSUPPORTED
    assert missing in result.message


def test_keep_files_reports_the_folder(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    (tmp_path / "out.txt").write_text(POPF_OUTPUT)
    exe = _script(tmp_path, f"cat {tmp_path}/out.txt\n")
    result = PopfSolver({"executable": exe, "keep_files": True}).solve(domain, problem, 10)
    kept = Path(result.message.rsplit("files kept in ", 1)[1].rstrip(")"))
    assert (kept / "domain.pddl").read_text().startswith("(define (domain fleet)")
    assert (kept / "problem.pddl").is_file()
    for f in kept.iterdir():
        f.unlink()
    kept.rmdir()
