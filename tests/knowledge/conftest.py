"""Fixtures for the knowledge tests: PlanSys2's own test domains and problems."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from knowledge_paths import PROBLEM_EXPERT_PDDL

from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import ProblemExpert


@pytest.fixture
def pe_domain() -> Callable[[str], DomainExpert]:
    """A domain expert for a domain of plansys2_problem_expert's tests."""

    def load(name: str) -> DomainExpert:
        return DomainExpert.from_files([PROBLEM_EXPERT_PDDL / name])

    return load


@pytest.fixture
def simple() -> ProblemExpert:
    """An empty problem expert on plansys2_problem_expert's domain_simple.pddl."""
    return ProblemExpert(DomainExpert.from_files([PROBLEM_EXPERT_PDDL / "domain_simple.pddl"]))
