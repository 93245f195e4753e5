"""Errors name file:line:col and quote the offending text."""

from __future__ import annotations

import pytest

from plansys_bridge.errors import PddlError, PddlSemanticError, PddlSyntaxError
from plansys_bridge.pddl.model import Action, Atom
from plansys_bridge.pddl.parser import parse_domain, parse_problem

DOMAIN = """\
(define (domain rooms)
  (:requirements :typing :durative-actions :fluents)
  (:types room corridor - place robot)
  (:constants base - place)
  (:predicates (robot_at ?r - robot ?p - place) (connected ?a ?b - place))
  (:functions (battery ?r - robot))
  (:durative-action move
    :parameters (?r - robot ?from ?to - place)
    :duration (= ?duration 5)
    :condition (and (at start (robot_at ?r ?from)) (at start (connected ?from ?to)))
    :effect (and (at start (not (robot_at ?r ?from))) (at end (robot_at ?r ?to))
                 (at end (decrease (battery ?r) 1))))
)
"""


def _action(body: str, domain: str = DOMAIN) -> str:
    """``domain`` with one more plain action whose precondition is ``body`` (line 13)."""
    lines = domain.splitlines()
    extra = f"  (:action probe :parameters (?r - robot ?x - room) :precondition {body})"
    return "\n".join([*lines[:12], extra, *lines[12:]]) + "\n"


def _error(text: str, kind: type[PddlError] = PddlSemanticError) -> PddlError:
    with pytest.raises(kind) as info:
        parse_domain(text, "d.pddl")
    return info.value


def _at(text: str, line: int, marker: str, after: str = "") -> tuple[int, int]:
    """Line and column of ``marker`` on ``line`` (first one after ``after``)."""
    source = text.splitlines()[line - 1]
    return line, source.index(marker, source.index(after) if after else 0) + 1


def _where(err: PddlError) -> tuple[int, int]:
    assert err.location is not None
    assert err.location.file == "d.pddl"
    return err.location.line, err.location.column


def test_the_base_domain_is_valid() -> None:
    domain = parse_domain(_action("(robot_at ?r ?x)"))
    assert [a.name for a in domain.actions] == ["move", "probe"]


@pytest.mark.parametrize(
    ("body", "at", "words"),
    [
        ("(robot_att ?r ?x)", "robot_att", "unknown predicate 'robot_att'"),
        ("(robot_at ?r)", "robot_at", "takes 2 argument(s)"),
        ("(robot_at ?r ?y)", "?y", "undeclared variable ?y"),
        (
            "(robot_at ?x ?r)",
            "?x ?r",
            "?x is a room but argument 1 of predicate 'robot_at' must be a robot",
        ),
        ("(robot_at base ?x)", "base", "'base' is a place but argument 1"),
        ("(> (charge ?r) 3)", "charge", "unknown function 'charge'"),
        ("(> (battery ?x) 3)", "?x)", "?x is a room but argument 1 of function 'battery'"),
        ("(exists (?z - hall) (robot_at ?r ?z))", "?z", "unknown type 'hall'"),
        ("(and (robot_at ?r ?x) (= ?r ?q))", "probe", "undeclared variable ?q"),
    ],
)
def test_semantic_errors_point_at_the_offender(body: str, at: str, words: str) -> None:
    text = _action(body)
    line = text.splitlines()[12]
    column = line.index(at, line.index(":precondition") if at != "probe" else 0) + 1
    err = _error(text)
    assert _where(err) == (13, column), str(err)
    assert words in err.message
    assert err.snippet is not None
    source_line, caret_line = err.snippet.splitlines()
    assert source_line.endswith(line.rstrip())
    assert caret_line.index("^") == source_line.index("|") + 2 + column - 1


def test_unknown_names_in_a_domain_are_left_to_the_problem() -> None:
    domain = parse_domain(_action("(robot_at ?r nowhere)"))
    [probe] = [a for a in domain.actions if a.name == "probe"]
    assert isinstance(probe, Action)
    assert probe.precondition == Atom("robot_at", ("?r", "nowhere"))


def test_subtypes_and_either_are_respected() -> None:
    parse_domain(_action("(and (robot_at ?r ?x) (connected ?x base))"))  # room is a place
    text = DOMAIN.replace(
        "(connected ?a ?b - place))", "(connected ?a ?b - place) (lit ?p - (either room robot)))"
    )
    parse_domain(_action("(and (lit ?x) (lit ?r))", text))
    err = _error(_action("(exists (?c - corridor) (lit ?c))", text))
    assert "?c is a corridor" in err.message and "(either room robot)" in err.message


def test_durative_action_needs_its_requirement() -> None:
    err = _error(DOMAIN.replace(" :durative-actions", ""))
    assert _where(err) == (7, 21)
    assert ":durative-actions" in err.message


def test_using_fluents_needs_a_numeric_requirement_but_declaring_them_does_not() -> None:
    no_fluents = DOMAIN.replace(" :fluents", "")
    err = _error(no_fluents)
    assert _where(err) == _at(no_fluents, 12, "battery")
    assert ":numeric-fluents" in err.message
    lines = no_fluents.splitlines()
    parse_domain("\n".join(lines[:6]) + "\n)")  # (:functions ...) alone is fine


def test_unknown_requirement_is_located() -> None:
    err = _error(DOMAIN.replace(":fluents", ":fluent"))
    assert _where(err) == _at(DOMAIN, 2, ":fluents")
    assert "unknown requirement ':fluent'" in err.message


def test_duplicate_definitions_conflict_or_merge() -> None:
    same = DOMAIN.replace("(:functions", "(:predicates (connected ?x ?y - place))\n  (:functions")
    assert len(parse_domain(same).predicates) == 2
    other = DOMAIN.replace("(:functions", "(:predicates (connected ?x - place))\n  (:functions")
    err = _error(other)
    assert "conflicting definitions of predicate 'connected'" in err.message
    assert "d.pddl:5:50" in err.message and _where(err) == (6, 17)


def test_type_cycle_is_rejected() -> None:
    err = _error(DOMAIN.replace("(:types room corridor - place robot)", "(:types a - b b - a)"))
    assert "cycle" in err.message


def test_duplicate_parameter_is_rejected() -> None:
    err = _error(DOMAIN.replace("?from ?to - place", "?from ?from - place"))
    assert "?from declared twice" in err.message and _where(err) == (8, 35)


def test_effect_on_derived_predicate_is_rejected() -> None:
    text = DOMAIN.replace(":fluents)", ":fluents :derived-predicates)").replace(
        "(:functions", "(:derived (connected ?a ?b - place) (= ?a ?b))\n  (:functions"
    )
    parse_domain(text)
    err = _error(text.replace("(at end (robot_at ?r ?to))", "(at end (connected ?to ?from))"))
    assert "derived predicate 'connected' cannot be changed" in err.message


@pytest.mark.parametrize(
    ("text", "where", "words"),
    [
        ("(define (domain d) (:predicates (p ?x))", (1, 40), "unexpected end of text"),
        ("(define (domain d)\n  (:predicates (p ?x) - t))", (2, 23), "unexpected '-'"),
        ("(define (domain d) (:predicates (p ?x))\n  (:action a :effect (p a) ))\n  ]", (3, 3), ""),
        ("(define (domain d)\n  (:action a :parameters (?x :effect (p ?x)))", (2, 30), "':effect'"),
        ("(define (domain d)\n  (:predicates (p ?x)) $", (2, 24), "unexpected character '$'"),
        ("(define (domain d)\n  (:durative-action a :duration (= ?d 1)))", (2, 36), "?duration"),
    ],
)
def test_syntax_errors(text: str, where: tuple[int, int], words: str) -> None:
    if where == (3, 3):
        parse_domain(text)  # text after the closing parenthesis is ignored
        return
    err = _error(text, PddlSyntaxError)
    assert _where(err) == where, str(err)
    assert words in err.message


def test_case_is_ignored_but_snippets_show_the_original() -> None:
    domain = parse_domain(DOMAIN.replace("robot_at", "Robot_AT").replace("(define", "(DEFINE"))
    assert "robot_at" in {p.name for p in domain.predicates}
    err = _error(_action("(Robot_Att ?R ?x)"))
    assert "'robot_att'" in err.message and "(Robot_Att ?R ?x)" in (err.snippet or "")


PROBLEM = """\
(define (problem p1) (:domain rooms)
  (:objects r2d2 - robot kitchen - room hall - corridor)
  (:init (robot_at r2d2 kitchen) (connected kitchen hall) (= (battery r2d2) 80))
  (:goal (and (robot_at r2d2 hall) (> (battery r2d2) 10)))
  (:metric minimize (total-time)))
"""


def test_problem_checks() -> None:
    domain = parse_domain(DOMAIN)
    problem = parse_problem(PROBLEM, domain, "p.pddl")
    assert problem.init_fluents[0].value == 80.0
    cases = [
        (
            ("(robot_at r2d2 hall)", "(robot_at r2d2 garden)"),
            (4, "garden"),
            "unknown object 'garden'",
        ),
        (
            ("(connected kitchen hall)", "(connected kitchen r2d2)"),
            (3, "r2d2)"),
            "'r2d2' is a robot",
        ),
        (("(= (battery r2d2)", "(= (battery kitchen)"), (3, "kitchen) 80"), "'kitchen' is a room"),
        (("hall - corridor", "hall - cave"), (2, "hall"), "unknown type 'cave'"),
        (("hall - corridor", "hall - corridor kitchen - corridor"), (2, "kitchen - c"), "already"),
        (("(robot_at r2d2 kitchen)", "(robot_at r2d2)"), (3, "robot_at"), "takes 2"),
    ]
    for (old, new), (line, marker), words in cases:
        text = PROBLEM.replace(old, new)
        where = _at(text, line, marker)
        with pytest.raises(PddlSemanticError) as info:
            parse_problem(text, domain, "p.pddl")
        loc = info.value.location
        assert loc is not None and (loc.line, loc.column) == where, str(info.value)
        assert words in info.value.message
