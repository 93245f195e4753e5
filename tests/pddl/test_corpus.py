"""Every PlanSys2 domain and problem parses and round-trips; the broken ones are
rejected with a file:line:col error."""

from __future__ import annotations

from pathlib import Path

import pytest
from pddl_corpus import CORPUS, candidate_domains, files, good_domains, is_broken, rel

from plansys_bridge.errors import PddlError, PddlSyntaxError
from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.pddl.writer import write_domain, write_problem

pytestmark = pytest.mark.skipif(CORPUS is None, reason="PlanSys2 PDDL corpus not found")

DOMAINS = files("domain")
PROBLEMS = files("problem")


def test_corpus_is_complete() -> None:
    assert len(DOMAINS) >= 40
    assert len(PROBLEMS) >= 30
    assert sum(map(is_broken, DOMAINS + PROBLEMS)) == 10


@pytest.mark.parametrize("path", [p for p in DOMAINS if not is_broken(p)], ids=rel)
def test_domain_parses_and_round_trips(path: Path) -> None:
    domain = good_domains()[path]
    assert domain.name
    assert domain.predicates or domain.actions
    text = write_domain(domain)
    assert parse_domain(text, "<written>") == domain
    assert write_domain(parse_domain(text)) == text


@pytest.mark.parametrize("path", [p for p in DOMAINS if is_broken(p)], ids=rel)
def test_broken_domain_is_rejected_with_location(path: Path) -> None:
    with pytest.raises(PddlError) as info:
        parse_domain(path.read_text(encoding="utf-8"), rel(path))
    err = info.value
    assert err.location is not None and err.location.file == rel(path)
    assert err.location.line > 1 and err.location.column >= 1
    assert err.snippet and "^" in err.snippet
    assert str(err).startswith(f"{rel(path)}:{err.location.line}:{err.location.column}: ")


@pytest.mark.parametrize("path", [p for p in PROBLEMS if not is_broken(p)], ids=rel)
def test_problem_parses_against_a_domain_and_round_trips(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    errors: list[str] = []
    for _, domain in candidate_domains(path):
        try:
            problem = parse_problem(text, domain, rel(path))
        except PddlError as exc:
            errors.append(str(exc))
            continue
        assert problem.name
        written = write_problem(problem)
        assert parse_problem(written, domain) == problem
        return
    pytest.fail(f"no corpus domain accepts {rel(path)}:\n" + "\n".join(errors[:3]))


@pytest.mark.parametrize("path", [p for p in PROBLEMS if is_broken(p)], ids=rel)
def test_broken_problem_is_rejected_by_every_domain(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    for _, domain in candidate_domains(path):
        with pytest.raises(PddlError) as info:
            parse_problem(text, domain, rel(path))
        loc = info.value.location
        assert loc is not None and loc.file == rel(path) and loc.line > 1


def test_misspelt_goal_is_a_syntax_error_at_its_place() -> None:
    path = next(p for p in PROBLEMS if p.name == "problem_simple_3.pddl")
    with pytest.raises(PddlSyntaxError) as info:
        parse_problem(path.read_text(encoding="utf-8"), None, "p3.pddl")
    assert (info.value.location.line, info.value.location.column) == (14, 4)  # type: ignore[union-attr]
    assert "':goa'" in info.value.message and "':goal'" in info.value.message


def test_cooking_problem_with_trailing_commands_parses() -> None:
    path = next(p for p in PROBLEMS if p.name == "cooking_problem_0.pddl")
    text = path.read_text(encoding="utf-8")
    assert ";;set goal" in text  # terminal commands, commented out, after the definition
    domain = candidate_domains(path)[0][1]
    problem = parse_problem(text, domain, rel(path))
    assert problem.goal
    # PlanSys2 ignores any text after the closing parenthesis, not only comments.
    tail = ')\nset instance r2d2 robot\n"unbalanced ( text ?'
    assert parse_problem(text + tail, domain, rel(path)) == problem


def test_multidomain_example_merges() -> None:
    from plansys_bridge.pddl.parser import parse_domain_files

    assert CORPUS is not None
    base = CORPUS / "ros2_planning_system_examples/plansys2_multidomain_example"
    merged = parse_domain_files([base / "pddl_1/domain_1.pddl", base / "pddl_2/domain_2.pddl"])
    assert merged.name == "multidomain1_multidomain2"
    assert {a.name for a in merged.actions} == {
        "move",
        "askcharge",
        "charge",
        "pick_object",
        "place_object",
    }
    assert [p.name for p in merged.predicates].count("robot_at") == 1
    assert parse_domain(write_domain(merged)) == merged
