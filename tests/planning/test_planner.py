"""The planner: solver choice by features, options, fallback, threads, anytime budget."""

from __future__ import annotations

import stat
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import tasks

from plansys_bridge.errors import ConfigError, PluginError
from plansys_bridge.planning.capabilities import Capability, required_capabilities
from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.solvers import DEFAULT_ORDER, load_solver


def test_default_is_kairos() -> None:
    domain, problem = tasks.temporal()
    result = Planner().solve(domain, problem)
    assert DEFAULT_ORDER[0] == "kairos"
    assert result.status is PlanStatus.SOLVED and result.solver == "kairos"
    assert result.plan is not None and result.plan.makespan == pytest.approx(15.0, abs=0.002)


def test_required_capabilities() -> None:
    assert required_capabilities(*tasks.classical()) == frozenset()
    assert required_capabilities(*tasks.temporal()) == {Capability.DURATIVE_ACTIONS}
    assert required_capabilities(*tasks.numeric()) == {
        Capability.DURATIVE_ACTIONS,
        Capability.NUMERIC_FLUENTS,
    }
    assert Capability.REQUIRED_CONCURRENCY in required_capabilities(*tasks.concurrent())


def test_first_solver_that_fits_is_used() -> None:
    domain, problem = tasks.temporal()
    result = Planner(["fast-downward", "kairos"]).solve(domain, problem)
    assert result.status is PlanStatus.SOLVED
    assert result.solver == "kairos"
    domain, problem = tasks.classical()
    if load_solver("fast-downward").unavailable_reason() is None:
        assert Planner(["fast-downward", "kairos"]).solve(domain, problem).solver == "fast-downward"


def test_no_solver_fits() -> None:
    domain, problem = tasks.numeric()
    result = Planner(["fast-downward", "popf"], options={}).solve(domain, problem)
    assert result.status is PlanStatus.UNSUPPORTED
    assert result.plan is None
    assert "fast-downward does not support :durative-actions :numeric-fluents" in result.message
    assert "popf" in result.message


def test_unknown_solver() -> None:
    with pytest.raises(PluginError, match=r"unknown solver 'nope'.*kairos"):
        Planner(["nope"])


def test_options() -> None:
    planner = Planner(["kairos", "lpg"], options={"kairos": {"threads": 1}, "seed": 3})
    kairos, lpg = planner.solvers
    assert kairos.options == {"threads": 1, "seed": 3}
    assert lpg.options == {"seed": 3}
    with pytest.raises(ConfigError) as err:
        Planner(["kairos"], options={"kairos": {"bogus": 1}})
    assert err.value.key == "solvers.kairos.bogus"
    with pytest.raises(ConfigError) as err:
        Planner(["kairos"], options={"alias": "lama"})
    assert err.value.key == "solvers.alias"
    with pytest.raises(ConfigError):
        Planner(timeout=0)


def test_validate_attaches_the_report() -> None:
    domain, problem = tasks.temporal()
    result = Planner(validate=True).solve(domain, problem)
    assert result.validation is not None and result.validation.valid


def _failing_popf(tmp_path: Path) -> str:
    path = tmp_path / "popf"
    path.write_text("#!/bin/sh\necho 'popf: out of memory' >&2\nexit 1\n")
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return str(path)


def test_fallback_to_the_next_solver(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    options = {"popf": {"executable": _failing_popf(tmp_path)}}
    failed = Planner(["popf", "kairos"], options=options).solve(domain, problem)
    assert failed.status is PlanStatus.ERROR and failed.solver == "popf"
    assert "exited with status 1" in failed.message and "out of memory" in failed.message
    rescued = Planner(["popf", "kairos"], options=options, fallback=True).solve(domain, problem)
    assert rescued.status is PlanStatus.SOLVED and rescued.solver == "kairos"
    assert "out of memory" in rescued.message


def test_unsolvable() -> None:
    domain, problem = tasks.classical_unsolvable()
    result = Planner().solve(domain, problem)
    assert result.status is PlanStatus.UNSOLVABLE
    assert "kairos" in result.message


def test_usable_from_threads() -> None:
    planner = Planner()
    loaded = [tasks.temporal(), tasks.numeric(), tasks.concurrent(), tasks.classical()]
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda t: planner.solve(*t), loaded * 2))
    assert all(r.status is PlanStatus.SOLVED for r in results)
    assert [len(r.plan or ()) for r in results[:4]] == [len(r.plan or ()) for r in results[4:]]


def test_anytime_budget_never_worse() -> None:
    domain, problem = tasks.temporal()
    first = Planner().solve(domain, problem)
    improved = Planner(options={"improve_for": 0.5}).solve(domain, problem)
    assert improved.status is PlanStatus.SOLVED
    assert first.plan is not None and improved.plan is not None
    assert improved.plan.makespan <= first.plan.makespan + 1e-9
