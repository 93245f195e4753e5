"""Where PlanSys2's PDDL corpus lives and which of its files must be rejected.

Shared by every test folder (tests/ is on the import path through its conftest).

The corpus (tests/fixtures/plansys2, or $PLANSYS_BRIDGE_FIXTURES) keeps the
repository-relative paths of PlanSys2's repositories. The broken files are the
ones tests/fixtures/README.md lists.
"""

from __future__ import annotations

import os
import re
from functools import cache
from pathlib import Path

from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain

FIXTURES = Path(
    os.environ.get("PLANSYS_BRIDGE_FIXTURES")
    or Path(__file__).resolve().parent / "fixtures" / "plansys2"
)
"""Where the corpus should be (tests that need particular files read them from here)."""

CORPUS = FIXTURES if FIXTURES.is_dir() else None
"""The corpus, or None when it is missing (the corpus-wide tests then have no cases)."""

_KIND = re.compile(r"\(\s*define\s*\(\s*(domain|problem)\b", re.IGNORECASE)

# PlanSys2's domain_simple_derived.pddl applies inferred-robot_at (robot, room) to
# two rooms; its *_processed.pddl twin is PlanSys2's own merge output of that same
# file and carries the same type error.
_BROKEN_DOMAINS = {
    "ros2_planning_system/plansys2_domain_expert/test/pddl/domain_simple_derived.pddl",
    "ros2_planning_system/plansys2_domain_expert/test/pddl/domain_simple_derived_processed.pddl",
}


def rel(path: Path) -> str:
    assert CORPUS is not None
    return path.relative_to(CORPUS).as_posix()


def is_broken(path: Path) -> bool:
    name = path.name
    return (
        "error" in name
        or name in ("problem_unexpected_syntax.pddl", "problem_simple_3.pddl")
        or rel(path) in _BROKEN_DOMAINS
    )


def kind(path: Path) -> str:
    match = _KIND.search(path.read_text(encoding="utf-8"))
    assert match, f"{path} is neither a domain nor a problem"
    return match.group(1).lower()


def files(which: str) -> list[Path]:
    if CORPUS is None:
        return []
    return sorted(p for p in CORPUS.rglob("*.pddl") if kind(p) == which)


@cache
def good_domains() -> dict[Path, Domain]:
    return {
        p: parse_domain(p.read_text(encoding="utf-8"), rel(p))
        for p in files("domain")
        if not is_broken(p)
    }


def candidate_domains(problem: Path) -> list[tuple[Path, Domain]]:
    """Domains to try for a problem: its own folder first, then the rest."""
    domains = good_domains()
    near = [(p, d) for p, d in domains.items() if p.parent == problem.parent]
    far = [(p, d) for p, d in domains.items() if p.parent != problem.parent]
    return near + far
