"""Where PlanSys2's test PDDL files are (shared by the knowledge tests)."""

from __future__ import annotations

import os
from pathlib import Path

# The corpus lives in shared/ beside the repository (or where $PLANSYS_BRIDGE_FIXTURES says).
PLANSYS2 = Path(
    os.environ.get("PLANSYS_BRIDGE_FIXTURES")
    or Path(__file__).resolve().parents[3] / "shared" / "fixtures" / "plansys2"
)
PROBLEM_EXPERT_PDDL = PLANSYS2 / "ros2_planning_system/plansys2_problem_expert/test/pddl"
DOMAIN_EXPERT_PDDL = PLANSYS2 / "ros2_planning_system/plansys2_domain_expert/test/pddl"


def read(path: Path) -> str:
    return path.read_text(encoding="utf-8")
