"""Where PlanSys2's test PDDL files are (shared by the knowledge tests)."""

from __future__ import annotations

from pathlib import Path

from pddl_corpus import FIXTURES as PLANSYS2

PROBLEM_EXPERT_PDDL = PLANSYS2 / "ros2_planning_system/plansys2_problem_expert/test/pddl"
DOMAIN_EXPERT_PDDL = PLANSYS2 / "ros2_planning_system/plansys2_domain_expert/test/pddl"


def read(path: Path) -> str:
    return path.read_text(encoding="utf-8")
