"""The test suite every solver plugin passes (skipped, saying why, when it is absent).

For each registered solver: it plans every small task whose features it declares,
and the plan validates with the solver's own separation; it refuses tasks with
features it does not declare, naming them; it never reports a plan for an
unsolvable task; it rejects unknown options with the offending key.
unified-planning starts a Python process and imports every engine, so it gets the
solvable classical task only (its smoke test).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest
import tasks

from plansys_bridge.errors import ConfigError
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.planning.capabilities import ALL_CAPABILITIES, required_capabilities
from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.solvers import Solver, load_solver, solver_names
from plansys_bridge.planning.validation import validate_plan

SLOW = {"unified-planning"}
TASKS: dict[str, Callable[[], tuple[Domain, Problem]]] = {
    "classical": tasks.classical,
    "temporal": tasks.temporal,
    "numeric": tasks.numeric,
    "concurrent": tasks.concurrent,
}


@pytest.fixture(params=solver_names())
def solver_class(request: pytest.FixtureRequest) -> type[Solver]:
    cls = load_solver(request.param)
    reason = cls.unavailable_reason()
    if reason is not None:
        pytest.skip(f"{request.param}: {reason}")
    return cls


def test_declarations(solver_class: type[Solver]) -> None:
    assert solver_class.name in solver_names()
    assert solver_class.capabilities <= ALL_CAPABILITIES
    assert solver_class.epsilon > 0


@pytest.mark.parametrize("task", sorted(TASKS))
def test_plans_what_it_supports(solver_class: type[Solver], task: str) -> None:
    domain, problem = TASKS[task]()
    # a solver that searches at random (LPG-td) is seeded: one run, one answer
    solver = solver_class({"seed": 1} if "seed" in solver_class.option_types else None)
    missing = solver.missing_capabilities(required_capabilities(domain, problem))
    if solver_class.name in SLOW and (missing or task != "classical"):
        pytest.skip("slow engine: covered by its classical smoke test")
    result = solver.solve(domain, problem, timeout=20)
    assert result.solver == solver_class.name
    assert result.elapsed_s >= 0
    if missing:
        assert result.status is PlanStatus.UNSUPPORTED
        assert all(str(cap) in result.message for cap in missing), result.message
        return
    assert result.status is PlanStatus.SOLVED, str(result)
    assert result.plan is not None and len(result.plan) > 0
    report = validate_plan(domain, problem, result.plan, epsilon=solver_class.epsilon)
    assert report.valid, f"{report.message}\n{result.plan.to_text(4)}"


def test_unsolvable_is_never_solved(solver_class: type[Solver]) -> None:
    if solver_class.name in SLOW:
        pytest.skip("slow engine: covered by its classical smoke test")
    domain, problem = tasks.classical_unsolvable()
    solver = solver_class()
    result = solver.solve(domain, problem, timeout=20)
    assert result.status is not PlanStatus.SOLVED
    assert result.plan is None
    assert result.message
    if not solver.missing_capabilities(required_capabilities(domain, problem)):
        # LPG-td crashes on unsolvable tasks; that is an error with its exit status
        assert result.status in (PlanStatus.UNSOLVABLE, PlanStatus.ERROR), str(result)


def test_unknown_option_names_the_key(solver_class: type[Solver]) -> None:
    with pytest.raises(ConfigError) as err:
        solver_class({"no_such_option": 1})
    assert err.value.key == f"solvers.{solver_class.name}.no_such_option"


def test_wrong_option_type_names_the_key(solver_class: type[Solver]) -> None:
    fields = solver_class.Settings.model_fields
    if not fields:
        pytest.skip("no options")
    key, field = sorted(fields.items())[0]
    wrong: object = 3 if "str" in str(field.annotation) else "text"
    with pytest.raises(ConfigError) as err:
        solver_class({key: wrong})
    assert err.value.key == f"solvers.{solver_class.name}.{key}"
