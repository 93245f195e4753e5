"""The domain expert, mirroring plansys2_domain_expert's tests."""

from __future__ import annotations

import pytest
from knowledge_paths import DOMAIN_EXPERT_PDDL, PROBLEM_EXPERT_PDDL

from plansys_bridge.errors import PddlError
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.pddl.model import Action, DurativeAction, TypedName
from plansys_bridge.pddl.parser import parse_domain


@pytest.fixture(scope="module")
def simple() -> DomainExpert:
    return DomainExpert.from_files([DOMAIN_EXPERT_PDDL / "domain_simple.pddl"])


def test_get_types(simple: DomainExpert) -> None:
    assert simple.get_types() == ["person", "message", "robot", "room", "teleporter_room"]
    assert simple.get_subtypes("room") == ["teleporter_room"]
    assert simple.get_subtypes("ROOM") == ["teleporter_room"]
    assert simple.get_subtypes("robot") == []
    assert set(simple.get_subtypes("object")) == set(simple.get_types())
    assert simple.is_valid_type("Teleporter_Room") and not simple.is_valid_type("scientific")


def test_get_predicates(simple: DomainExpert) -> None:
    assert [p.name for p in simple.get_predicates()] == [
        "robot_talk",
        "robot_near_person",
        "robot_at",
        "person_at",
    ]
    robot_talk = simple.get_predicate("ROBOT_TALK")
    assert robot_talk is not None
    assert robot_talk.parameters == (
        TypedName("?r", ("robot",)),
        TypedName("?m", ("message",)),
        TypedName("?p", ("person",)),
    )
    assert simple.get_predicate("robot_talk_2") is None


def test_get_functions(simple: DomainExpert) -> None:
    assert [f.name for f in simple.get_functions()] == ["teleportation_time"]
    f = simple.get_function("teleportation_time")
    assert f is not None
    assert [p.types for p in f.parameters] == [("teleporter_room",), ("room",)]
    assert simple.get_function("nope") is None


def test_get_actions(simple: DomainExpert) -> None:
    assert [a.name for a in simple.get_actions()] == ["move_person"]
    assert [a.name for a in simple.get_durative_actions()] == ["move", "talk", "approach"]
    move = simple.get_action("move")
    assert isinstance(move, DurativeAction)
    assert [p.name for p in move.parameters] == ["?r", "?r1", "?r2"]
    assert isinstance(simple.get_action("MOVE_PERSON"), Action)
    assert simple.get_action("fly") is None


def test_constants() -> None:
    de = DomainExpert.from_files([DOMAIN_EXPERT_PDDL / "domain_simple_constants.pddl"])
    assert de.get_constants() == ["leia", "lema", "jack", "john"]
    assert de.get_constants("robot") == ["leia", "lema"]
    assert de.get_constants("person") == ["jack", "john"]
    assert de.get_constants("room") == []
    assert de.constant_type("LEIA") == "robot"


def test_derived_predicates() -> None:
    de = DomainExpert.from_files([PROBLEM_EXPERT_PDDL / "domain_simple_derived.pddl"])
    assert [r.head.name for r in de.get_derived()] == ["inferred-robot_at", "inferred-person_at"]
    assert len(de.get_derived("inferred-robot_at")) == 1
    assert de.is_derived("inferred-person_at") and not de.is_derived("person_at")
    assert de.get_predicate("inferred-robot_at") is not None


def test_merged_domains_and_text() -> None:
    first, second = (
        DOMAIN_EXPERT_PDDL / "domain_simple.pddl",
        DOMAIN_EXPERT_PDDL / "domain_simple_ext.pddl",
    )
    de = DomainExpert.from_files(f"{first}:{second}")
    assert {"pickable_object", "robot", "room"} <= set(de.get_types())
    assert {a.name for a in de.get_durative_actions()} >= {"move", "pick_object", "place_object"}
    again = parse_domain(de.get_domain_text())
    assert again == de.domain


def test_bad_domain_is_refused() -> None:
    with pytest.raises(PddlError):
        DomainExpert.from_files([DOMAIN_EXPERT_PDDL / "domain_2_error.pddl"])
    with pytest.raises(PddlError):
        DomainExpert.from_text("(define (domain x) (:predicates (p ?x - nosuchtype)))")
