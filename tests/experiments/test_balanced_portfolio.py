"""The cooking portfolio balances each configuration's plan and keeps the one its robots
finish first: two omelettes cooked by two robots at once, not one after the other."""

from __future__ import annotations

import random
from collections.abc import Sequence
from typing import TypeVar

import pytest

from plansys_bridge.experiments.cooking import PORTFOLIO, PortfolioPlanner
from plansys_bridge.experiments.cooking_world import (
    PAPER_DURATIONS,
    cooking_domain_path,
    dish_order,
    robot_names,
    world_setup,
)
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.pddl.parser import parse_domain_files, parse_problem
from plansys_bridge.planning.balance import balance_plan, executed_makespan, overlapping_steps
from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.result import PlanResult, PlanStatus
from plansys_bridge.planning.validation import validate_plan

T = TypeVar("T")
SHORTEST_DISH = PAPER_DURATIONS["move"] + PAPER_DURATIONS["transport"] + PAPER_DURATIONS["cook"]


class _Omelettes(random.Random):
    """Orders omelettes only: a mission of two dishes of one kind."""

    def choice(self, seq: Sequence[T]) -> T:
        return next(x for x in seq if x == "omelette")


def two_omelettes(robots: int = 3) -> tuple[Domain, Problem]:
    domain = parse_domain_files([cooking_domain_path()])
    world = world_setup(robots)
    order = dish_order(1, _Omelettes(), 2, robot_names(robots))
    objects = " ".join(f"{n} - {t}" for n, t in {**world.instances, **order.instances}.items())
    init = " ".join(world.predicates + order.predicates)
    text = (
        f"(define (problem two) (:domain cooking) (:objects {objects}) (:init {init}) "
        f"(:goal {order.goal}))"
    )
    return domain, parse_problem(text, domain, "two.pddl")


class _Fixed(Planner):
    """A planner that answers with a given result (the portfolio's choice is tested)."""

    def __init__(self, result: PlanResult) -> None:
        super().__init__()
        self.result = result

    def solve(self, domain: Domain, problem: Problem) -> PlanResult:
        return self.result


def test_two_omelettes_are_cooked_by_two_robots_at_once() -> None:
    domain, problem = two_omelettes()
    result = PortfolioPlanner().solve(domain, problem)
    assert result.solved and result.plan is not None
    assert validate_plan(domain, problem, result.plan).valid
    assert overlapping_steps(result.plan) == []
    assert executed_makespan(result.plan) == pytest.approx(SHORTEST_DISH, abs=0.01)
    cooks = [s for s in result.plan if s.action == "cook_omelette"]
    assert len({s.arguments[0] for s in cooks}) == 2


def test_the_portfolio_keeps_the_best_balanced_plan_of_its_configurations() -> None:
    domain, problem = two_omelettes()
    planners = [Planner(), *(Planner(options={"kairos": dict(c)}) for c in PORTFOLIO)]
    made = []
    for planner in planners:
        plan = planner.solve(domain, problem).plan
        assert plan is not None
        made.append(balance_plan(domain, problem, plan).after)
    result = PortfolioPlanner().solve(domain, problem)
    assert result.plan is not None
    assert executed_makespan(result.plan) == pytest.approx(min(made))


def test_a_failing_configuration_does_not_hide_a_plan() -> None:
    domain, problem = two_omelettes()
    portfolio = PortfolioPlanner()
    failed = PlanResult(PlanStatus.ERROR, None, "kairos", "crashed", 0.0)
    portfolio.alternatives = [_Fixed(failed) for _ in portfolio.alternatives]
    result = portfolio.solve(domain, problem)
    assert result.solved and result.plan is not None
    assert validate_plan(domain, problem, result.plan).valid


def test_a_doubled_plan_from_a_configuration_is_balanced_before_the_choice() -> None:
    domain, problem = two_omelettes()
    first = Planner().solve(domain, problem)
    assert first.plan is not None
    # whichever configuration gave it, a plan with both cooks on one robot is repaired
    doubled = [s for s in first.plan if s.action == "cook_omelette"]
    if len({s.arguments[0] for s in doubled}) == 2:
        pytest.skip("Kairos' default plan already spreads the cooks over two robots")
    portfolio = PortfolioPlanner()
    portfolio.alternatives = [_Fixed(first) for _ in portfolio.alternatives]
    result = portfolio.solve(domain, problem)
    assert result.plan is not None
    assert executed_makespan(result.plan) < executed_makespan(first.plan)
    assert "balanced: 1 step(s) handed to a free robot" in result.message
