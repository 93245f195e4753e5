"""The small entry points the knowledge base and terminal use for strings."""

from __future__ import annotations

import threading

import pytest

from plansys_bridge.errors import PddlSemanticError, PddlSyntaxError
from plansys_bridge.pddl.model import (
    AddEffect,
    And,
    AndEffect,
    Atom,
    Compare,
    DeleteEffect,
    Equals,
    Exists,
    FluentRef,
    FluentValue,
    Number,
)
from plansys_bridge.pddl.parser import (
    parse_atom,
    parse_condition,
    parse_domain,
    parse_effect,
    parse_fluent_value,
)
from plansys_bridge.pddl.writer import write_atom, write_condition, write_effect

DOMAIN = parse_domain(
    """(define (domain k) (:requirements :typing :fluents :adl)
  (:types robot room) (:constants dock - room)
  (:predicates (robot_at ?r - robot ?ro - room) (dish_prepared ?d))
  (:functions (battery ?r - robot)))"""
)


def test_atom() -> None:
    atom = parse_atom("(Robot_At R1 Kitchen)", DOMAIN)
    assert atom == Atom("robot_at", ("r1", "kitchen"))
    assert atom.loc is not None and (atom.loc.line, atom.loc.column) == (1, 2)
    assert write_atom(atom) == "(robot_at r1 kitchen)"
    assert parse_atom("(robot_at r1 dock)", DOMAIN, objects={"r1": "robot"}) == Atom(
        "robot_at", ("r1", "dock")
    )


@pytest.mark.parametrize(
    ("text", "error", "words"),
    [
        ("(robot_at r1 ?x)", PddlSemanticError, "must be ground"),
        ("(robot_at r1)", PddlSemanticError, "takes 2"),
        ("(robot_at r1 kitchen", PddlSyntaxError, "unexpected end"),
        ("robot_at r1 kitchen", PddlSyntaxError, "unexpected"),
        ("(robot_at r1 kitchen) extra", PddlSyntaxError, "unexpected 'extra'"),
    ],
)
def test_bad_atoms(text: str, error: type[Exception], words: str) -> None:
    with pytest.raises(error, match=words):
        parse_atom(text, DOMAIN)


def test_atom_with_objects_checks_names_and_types() -> None:
    with pytest.raises(PddlSemanticError, match="unknown object 'r9'"):
        parse_atom("(robot_at r9 dock)", DOMAIN, objects={"r1": "robot"})
    with pytest.raises(PddlSemanticError, match="'dock' is a room but argument 1"):
        parse_atom("(robot_at dock dock)", DOMAIN, objects={})


def test_fluent_value() -> None:
    value = parse_fluent_value("(= (battery r1) 80)", DOMAIN)
    assert value == FluentValue(FluentRef("battery", ("r1",)), 80.0)
    assert parse_fluent_value("(= (battery r1) -2.5e1)").value == -25.0
    with pytest.raises(PddlSemanticError, match="unknown function"):
        parse_fluent_value("(= (charge r1) 80)", DOMAIN)
    with pytest.raises(PddlSyntaxError, match="'='"):
        parse_fluent_value("(< (battery r1) 80)", DOMAIN)


def test_goal_condition() -> None:
    goal = parse_condition("(and (dish_prepared d1))", DOMAIN)
    assert goal == And((Atom("dish_prepared", ("d1",)),))
    assert parse_condition(write_condition(goal), DOMAIN) == goal
    cond = parse_condition(
        "(and (exists (?r - robot) (robot_at ?r ?ro)) (> (battery r1) 10) (= ?ro dock))",
        DOMAIN,
        {"?ro": ("room",)},
    )
    assert isinstance(cond, And)
    assert isinstance(cond.operands[0], Exists)
    assert cond.operands[1] == Compare(">", FluentRef("battery", ("r1",)), Number(10.0))
    assert cond.operands[2] == Equals("?ro", "dock")
    with pytest.raises(PddlSemanticError, match="undeclared variable"):
        parse_condition("(robot_at r1 ?ro)", DOMAIN)
    with pytest.raises(PddlSemanticError, match="unknown object 'ghost'"):
        parse_condition("(dish_prepared ghost)", DOMAIN, objects={"d1": "object"})


def test_effect() -> None:
    eff = parse_effect(
        "(and (robot_at r1 k) (not (robot_at r1 h)) (increase (battery r1) 5))", DOMAIN
    )
    assert isinstance(eff, AndEffect)
    assert eff.effects[:2] == (
        AddEffect(Atom("robot_at", ("r1", "k"))),
        DeleteEffect(Atom("robot_at", ("r1", "h"))),
    )
    assert parse_effect(write_effect(eff), DOMAIN) == eff


def test_concurrent_parses_keep_their_file_names() -> None:
    errors: list[str] = []

    def work(name: str) -> None:
        for _ in range(30):
            try:
                parse_atom("(robot_at r1)", DOMAIN, filename=name)
            except PddlSemanticError as exc:
                assert exc.location is not None
                if exc.location.file != name:
                    errors.append(exc.location.file)

    threads = [threading.Thread(target=work, args=(f"t{i}",)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
