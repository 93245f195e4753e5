"""Merging domain files: identical repeats are fine, conflicts name both places."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import PddlSemanticError, PddlSyntaxError
from plansys_bridge.pddl.merge import merge_domains
from plansys_bridge.pddl.parser import parse_domain, parse_domain_files
from plansys_bridge.pddl.writer import write_domain

BASE = """\
(define (domain base)
  (:requirements :typing :durative-actions)
  (:types robot room - object)
  (:predicates (robot_at ?r - robot ?ro - room))
  (:durative-action move
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration 5)
    :condition (at start (robot_at ?r ?a))
    :effect (and (at start (not (robot_at ?r ?a))) (at end (robot_at ?r ?b))))
)
"""

EXTRA = """\
(define (domain extra)
  (:requirements :typing :adl)
  (:types robot room - object item)
  (:predicates (robot_at ?x - robot ?y - room) (holding ?r - robot ?i - item))
  (:action grab :parameters (?r - robot ?i - item)
    :precondition (not (holding ?r ?i)) :effect (holding ?r ?i))
)
"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_files_merge_with_identical_repeats(tmp_path: Path) -> None:
    merged = parse_domain_files(
        [_write(tmp_path, "a.pddl", BASE), _write(tmp_path, "b.pddl", EXTRA)]
    )
    assert merged.name == "base_extra"
    assert merged.requirements == (":typing", ":durative-actions", ":adl")
    assert [t.name for t in merged.types] == ["robot", "room", "item"]
    assert [p.name for p in merged.predicates] == ["robot_at", "holding"]
    assert [a.name for a in merged.actions] == ["move", "grab"]
    assert merged.source == f"{tmp_path / 'a.pddl'}:{tmp_path / 'b.pddl'}"
    assert parse_domain(write_domain(merged)) == merged


def test_a_file_may_use_types_of_another(tmp_path: Path) -> None:
    uses = EXTRA.replace("(:types robot room - object item)", "(:types item)")
    merged = parse_domain_files(
        [_write(tmp_path, "a.pddl", BASE), _write(tmp_path, "b.pddl", uses)]
    )
    assert {t.name for t in merged.types} == {"robot", "room", "item"}
    with pytest.raises(PddlSemanticError, match="unknown type 'robot'"):
        parse_domain(uses)


@pytest.mark.parametrize(
    ("old", "new", "kind", "line"),
    [
        ("(robot_at ?x - robot ?y - room)", "(robot_at ?x - robot)", "predicate 'robot_at'", 4),
        ("(:types robot room - object item)", "(:types robot - item room item)", "type 'robot'", 3),
        ("(:action grab", "(:action move", "action 'move'", 5),
    ],
)
def test_conflicting_definitions_name_both_places(
    tmp_path: Path, old: str, new: str, kind: str, line: int
) -> None:
    a = _write(tmp_path, "a.pddl", BASE)
    b = _write(tmp_path, "b.pddl", EXTRA.replace(old, new))
    with pytest.raises(PddlSemanticError) as info:
        parse_domain_files([a, b])
    err = info.value
    assert f"conflicting definitions of {kind}" in err.message
    assert f"{a}:" in err.message and f"{b}:{line}:" in err.message
    assert err.location is not None and err.location.file == str(b) and err.location.line == line
    assert err.snippet is not None


def test_syntax_error_in_one_file_names_that_file(tmp_path: Path) -> None:
    a = _write(tmp_path, "a.pddl", BASE)
    b = _write(tmp_path, "b.pddl", EXTRA.replace("(holding ?r ?i))\n)", "(holding ?r ?i)\n"))
    with pytest.raises(PddlSyntaxError) as info:
        parse_domain_files([a, b])
    assert info.value.location is not None and info.value.location.file == str(b)


def test_missing_file_is_a_pddl_error(tmp_path: Path) -> None:
    with pytest.raises(PddlSyntaxError, match="cannot read"):
        parse_domain_files([tmp_path / "nope.pddl"])


def test_merge_is_idempotent() -> None:
    domain = parse_domain(BASE)
    assert merge_domains([domain, domain]).actions == domain.actions
    assert merge_domains([domain]) == domain


def test_undeclared_parent_type_is_declared_under_object() -> None:
    domain = parse_domain(
        BASE.replace("(:types robot room - object)", "(:types robot room - place)")
    )
    assert [(t.name, t.parents) for t in domain.types] == [
        ("robot", ("place",)),
        ("room", ("place",)),
        ("place", ("object",)),
    ]
    assert parse_domain(write_domain(domain)) == domain
