"""PDDL that is wrong in the ways generated or damaged files are: every case is a
PddlError with file:line:col, never a RecursionError, a decoding error or a value
silently picked from two."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import PddlSemanticError, PddlSyntaxError
from plansys_bridge.pddl.diagnostics import SNIPPET_WIDTH
from plansys_bridge.pddl.parser import (
    MAX_NESTING,
    parse_condition,
    parse_domain,
    parse_domain_files,
    parse_problem,
)

DOMAIN = """\
(define (domain flat)
  (:requirements :strips :typing :fluents)
  (:types robot room)
  (:predicates (robot_at ?r - robot ?room - room))
  (:functions (travel_time ?a ?b - room))
  (:action go :parameters (?r - robot ?a ?b - room)
    :precondition (robot_at ?r ?a)
    :effect (and (not (robot_at ?r ?a)) (robot_at ?r ?b))))
"""


def _problem(init: str, goal: str = "(robot_at r k)") -> str:
    return (
        "(define (problem p) (:domain flat)\n"
        "  (:objects r - robot k h - room)\n"
        f"  (:init {init})\n"
        f"  (:goal {goal}))\n"
    )


def _nested(depth: int) -> str:
    return "(and " * depth + "(robot_at r k)" + ")" * depth


def test_nesting_up_to_the_limit_is_accepted() -> None:
    # the goal's atom sits at depth MAX_NESTING: define, :goal, then the and's
    goal = _nested(MAX_NESTING - 3)
    parse_problem(_problem("", goal), parse_domain(DOMAIN), "p.pddl")


def test_deeper_nesting_is_an_error_at_the_first_too_deep_parenthesis() -> None:
    text = _problem("", _nested(5000))
    with pytest.raises(PddlSyntaxError, match="nested more than 100 levels") as info:
        parse_problem(text, parse_domain(DOMAIN), "p.pddl")
    loc = info.value.location
    assert loc is not None and (loc.file, loc.line) == ("p.pddl", 4)
    assert loc.column == len("  (:goal ") + 5 * (MAX_NESTING - 2) + 1
    with pytest.raises(PddlSyntaxError, match="nested more than"):
        parse_condition(_nested(MAX_NESTING + 1), parse_domain(DOMAIN))


def test_a_comment_full_of_parentheses_does_not_count() -> None:
    domain = DOMAIN.replace("(:types", "; " + "(" * 500 + "\n  (:types")
    assert parse_domain(domain).name == "flat"


def test_binary_domain_file_names_the_first_bad_byte(tmp_path: Path) -> None:
    path = tmp_path / "d.pddl"
    path.write_bytes(b"(define (domain x)\n  (:requirements \x89PNG))\n")
    with pytest.raises(PddlSyntaxError, match="not UTF-8 text") as info:
        parse_domain_files([path])
    assert str(info.value.location) == f"{path}:2:18"


def test_a_byte_order_mark_moves_no_error_column(tmp_path: Path) -> None:
    path = tmp_path / "d.pddl"
    path.write_bytes(b"\xef\xbb\xbf(define (domain x) \x89)\n")
    with pytest.raises(PddlSyntaxError, match=r"not UTF-8 text \(byte 0x89\)") as info:
        parse_domain_files([path])
    assert str(info.value.location) == f"{path}:1:20"


def test_two_initial_values_for_one_fluent_are_an_error() -> None:
    domain = parse_domain(DOMAIN)
    text = _problem("(= (travel_time k h) 3) (= (travel_time k h) 4)")
    with pytest.raises(PddlSemanticError, match=r"\(travel_time k h\) is given two") as info:
        parse_problem(text, domain, "p.pddl")
    line = text.splitlines()[2]
    assert str(info.value.location) == f"p.pddl:3:{line.rindex('travel_time') + 1}"
    # the same value twice is harmless
    parse_problem(_problem("(= (travel_time k h) 3) (= (travel_time k h) 3)"), domain)


def test_number_too_large_for_a_float_is_an_error() -> None:
    with pytest.raises(PddlSyntaxError, match="number 1e999 is out of range") as info:
        parse_problem(_problem("(= (travel_time k h) 1e999)"), parse_domain(DOMAIN), "p.pddl")
    assert str(info.value.location) == "p.pddl:3:31"


def test_snippet_of_a_very_long_line_quotes_around_the_column() -> None:
    filler = " ".join(f"(robot_at r{i} k)" for i in range(200))
    text = _problem(filler, "(robot_at r q)").replace("(:objects r -", "(:objects r r0 -")
    one_line = " ".join(text.split())
    with pytest.raises(PddlSemanticError) as info:
        parse_problem(one_line, parse_domain(DOMAIN), "p.pddl")
    assert info.value.snippet is not None
    source, caret = info.value.snippet.splitlines()
    assert len(source) < SNIPPET_WIDTH + 20
    assert source[caret.index("^")] == "r"  # the caret still under the offender
