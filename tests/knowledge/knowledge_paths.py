"""Where PlanSys2's test PDDL files are (shared by the knowledge tests)."""

from __future__ import annotations

from pathlib import Path

PLANSYS2 = Path("/work/shared/fixtures/plansys2")
if not PLANSYS2.is_dir():  # the repository's own copy, when the shared one is absent
    PLANSYS2 = Path(__file__).resolve().parents[1] / "fixtures" / "plansys2"
PROBLEM_EXPERT_PDDL = PLANSYS2 / "ros2_planning_system/plansys2_problem_expert/test/pddl"
DOMAIN_EXPERT_PDDL = PLANSYS2 / "ros2_planning_system/plansys2_domain_expert/test/pddl"


def read(path: Path) -> str:
    return path.read_text(encoding="utf-8")
