"""Plan validation: timeline semantics, interference, the messages a user reads.

Verdicts on the temporal cases are cross-checked with VAL and ``kairos validate``
where both are installed, so the semantics are the community's, not ours alone.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import tasks
from planning_corpus import kairos_binary, kairos_verdict, val_binary, val_verdict

from plansys_bridge.pddl.model import Atom, Domain, Problem
from plansys_bridge.planning.plan import Plan, parse_plan
from plansys_bridge.planning.validation import ValidationReport, initial_state, validate_plan

EXTERNAL = val_binary() is not None and kairos_binary() is not None


def check(domain: Domain, problem: Problem, text: str, tmp_path: Path) -> ValidationReport:
    """Our verdict, asserted equal to VAL's and Kairos' when they are installed."""
    plan = parse_plan(text)
    report = validate_plan(domain, problem, plan)
    if EXTERNAL:
        assert val_verdict(tmp_path, domain, problem, plan) == report.valid, report.message
        assert kairos_verdict(tmp_path, domain, problem, plan) == report.valid, report.message
    return report


FLEET_OK = """
0.000: (move r1 base k1)  [5.000]
0.000: (move r2 base k2)  [5.000]
5.001: (clean r1 k1)  [10.000]
5.001: (clean r2 k2)  [10.000]
"""


def test_valid_parallel_plan(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    report = check(domain, problem, FLEET_OK, tmp_path)
    assert report.valid, report.message
    assert report.makespan == pytest.approx(15.001)
    assert report.failing_step is None and report.failing_condition is None
    assert bool(report)
    assert report.final_state is not None


def test_at_start_failure_names_step_and_condition(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    text = FLEET_OK.replace("5.001: (clean r2 k2)", "5.001: (clean r2 k1)")
    report = check(domain, problem, text, tmp_path)
    assert not report.valid
    assert report.failing_step is not None
    assert report.failing_step.text == "(clean r2 k1)"
    assert report.failing_condition == "(robot_at r2 k1)"
    assert "over all condition (robot_at r2 k1) is false" in report.message


def test_over_all_broken_by_another_action(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    text = """
0.000: (move r1 base k1)  [5.000]
5.001: (clean r1 k1)  [10.000]
8.000: (move r1 k1 base)  [5.000]
"""
    report = check(domain, problem, text, tmp_path)
    assert not report.valid
    assert report.failing_step is not None and report.failing_step.action == "clean"
    assert report.time == pytest.approx(8.0)
    assert "over all condition (robot_at r1 k1) is false at 8" in report.message


def test_over_all_may_start_when_its_achiever_ends(tmp_path: Path) -> None:
    # the invariant holds on the open interval: VAL and Kairos agree
    domain, problem = tasks.temporal()
    assert check(
        domain, problem, FLEET_OK.replace("5.001: (clean r1", "5.000: (clean r1"), tmp_path
    ).valid


SEQUENCE = "0.000: (move r1 a b)  [4.000]\nT: (move r1 b c)  [6.000]\n"


def test_happenings_at_the_same_time_must_not_interfere(tmp_path: Path) -> None:
    domain, problem = tasks.numeric()
    report = check(domain, problem, SEQUENCE.replace("T", "4.000"), tmp_path)
    assert not report.valid
    assert "at start condition (robot_at r1 b) is false" in report.message
    assert "the end of step 1 (move r1 a b) changes it at the same time" in report.message
    assert report.failing_step is not None and report.failing_step.arguments == ("r1", "b", "c")


def test_interfering_happenings_need_epsilon() -> None:
    domain, problem = tasks.numeric()
    close = parse_plan(SEQUENCE.replace("T", "4.0005"))
    report = validate_plan(domain, problem, close)
    assert not report.valid
    assert "only 0.0005 after the end of step 1 (move r1 a b)" in report.message
    assert "0.001 apart" in report.message
    assert validate_plan(domain, problem, close, epsilon=0.0004).valid
    assert not validate_plan(domain, problem, close, epsilon=0.0006).valid
    assert validate_plan(domain, problem, parse_plan(SEQUENCE.replace("T", "4.001"))).valid


def test_wrong_duration(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    report = check(
        domain,
        problem,
        FLEET_OK.replace("(move r1 base k1)  [5.000]", "(move r1 base k1)  [3.000]"),
        tmp_path,
    )
    assert not report.valid
    assert "duration 3 does not satisfy = 5" in report.message
    assert report.failing_condition == "(?duration = 5)"


def test_goal_not_reached(tmp_path: Path) -> None:
    domain, problem = tasks.temporal()
    text = "\n".join(FLEET_OK.strip().splitlines()[:3])
    report = check(domain, problem, text, tmp_path)
    assert not report.valid
    assert report.failing_step is None
    assert report.failing_condition == "(cleaned k2)"
    assert "goal is not reached: (cleaned k2) is false" in report.message


def test_numeric_condition_shows_values(tmp_path: Path) -> None:
    domain, problem = tasks.numeric()
    ok = "0.000: (move r1 a b)  [4.000]\n4.001: (move r1 b c)  [6.000]\n"
    assert check(domain, problem, ok, tmp_path).valid
    state = initial_state(domain, problem).with_changes(fluents={("battery", ("r1",)): 5.0})
    report = validate_plan(domain, problem, parse_plan(ok), state=state)
    assert not report.valid
    assert report.failing_step is not None and report.failing_step.arguments == ("r1", "b", "c")
    assert "[1 >= 6]" in report.message


def test_fluent_duration_is_checked(tmp_path: Path) -> None:
    domain, problem = tasks.numeric()
    bad = "0.000: (move r1 a b)  [5.000]\n5.001: (move r1 b c)  [6.000]\n"
    report = check(domain, problem, bad, tmp_path)
    assert not report.valid
    assert "does not satisfy = 4" in report.message


def test_required_concurrency(tmp_path: Path) -> None:
    domain, problem = tasks.concurrent()
    inside = "0.000: (light_match m1)  [8.000]\n0.001: (mend_fuse f1)  [5.000]\n"
    assert check(domain, problem, inside, tmp_path).valid
    after = "0.000: (light_match m1)  [8.000]\n8.001: (mend_fuse f1)  [5.000]\n"
    report = check(domain, problem, after, tmp_path)
    assert not report.valid
    assert "(light)" in report.message
    overrun = "0.000: (light_match m1)  [8.000]\n4.000: (mend_fuse f1)  [5.000]\n"
    report = check(domain, problem, overrun, tmp_path)
    assert not report.valid
    assert report.failing_step is not None and report.failing_step.action == "mend_fuse"


def test_classical_plan(tmp_path: Path) -> None:
    domain, problem = tasks.classical()
    report = check(domain, problem, "0: (go r1 a b)\n1: (go r1 b c)\n", tmp_path)
    assert report.valid, report.message
    report = check(domain, problem, "0: (go r1 b c)\n1: (go r1 a b)\n", tmp_path)
    assert not report.valid
    assert "precondition (at r1 b) is false" in report.message


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("0: (fly r1 a b)", "unknown action 'fly'"),
        ("0: (go r1 a)", "takes 3 arguments, got 2"),
        ("0: (go r1 a zz)", "unknown object 'zz'"),
        ("0: (go a r1 b)", "a is a room, parameter ?r wants robot"),
        ("-1: (go r1 a b)", "start time -1.0 is not a time >= 0"),
    ],
)
def test_bad_steps_are_named(text: str, expected: str) -> None:
    domain, problem = tasks.classical()
    report = validate_plan(domain, problem, parse_plan(text))
    assert not report.valid
    assert expected in report.message
    assert report.failing_index == 0
    assert "step 1" in report.message


def test_empty_plan_valid_only_when_goal_holds() -> None:
    domain, problem = tasks.classical()
    assert not validate_plan(domain, problem, Plan()).valid
    done = initial_state(domain, problem).with_changes(adds=[Atom("at", ("r1", "c"))])
    assert validate_plan(domain, problem, Plan(), state=done).valid
