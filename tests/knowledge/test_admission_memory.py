"""Effects applied again and again are checked once per set of objects.

The problem expert remembers the facts it admitted (see ``Admission.facts``); these
tests make sure the memory never lets through what the objects no longer allow:
an object removed, or put back with another type, is refused again, and a fact
that failed is not remembered as passed.
"""

from __future__ import annotations

import pytest

from plansys_bridge.errors import KnowledgeError
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Atom, Domain
from plansys_bridge.pddl.parser import parse_domain

DOMAIN_TEXT = """
(define (domain memo)
  (:requirements :strips :typing)
  (:types robot place)
  (:predicates (at ?r - robot ?p - place))
  (:action move
    :parameters (?r - robot ?to - place)
    :effect (at ?r ?to)))
"""


def _domain() -> Domain:
    return parse_domain(DOMAIN_TEXT)


def _expert() -> ProblemExpert:
    pe = ProblemExpert(_domain())
    pe.add_instance("r1", "robot")
    pe.add_instance("p1", "place")
    return pe


def _move(pe: ProblemExpert, to: str) -> None:
    pe.apply(pe.domain.actions[0].effect, {"?r": "r1", "?to": to})


def test_a_removed_object_is_refused_after_it_was_admitted() -> None:
    pe = _expert()
    _move(pe, "p1")
    assert pe.exist_predicate(Atom("at", ("r1", "p1")))
    pe.remove_instance("p1")
    with pytest.raises(KnowledgeError, match=r"unknown object 'p1'"):
        _move(pe, "p1")
    assert pe.get_predicates() == []


def test_an_object_put_back_with_another_type_is_refused() -> None:
    pe = _expert()
    _move(pe, "p1")
    pe.remove_instance("p1")
    pe.add_instance("p1", "robot")
    with pytest.raises(KnowledgeError, match=r"p1 is a robot, parameter \?p wants place"):
        _move(pe, "p1")


def test_an_undone_instance_is_refused_after_it_was_admitted() -> None:
    pe = _expert()
    with pytest.raises(KnowledgeError), pe.transaction():
        pe.add_instance("p2", "place")
        _move(pe, "p2")
        raise KnowledgeError("give up")
    with pytest.raises(KnowledgeError, match=r"unknown object 'p2'"):
        _move(pe, "p2")


def test_a_refused_fact_is_admitted_once_its_object_exists() -> None:
    pe = _expert()
    with pytest.raises(KnowledgeError, match=r"unknown object 'p2'"):
        _move(pe, "p2")
    pe.add_instance("p2", "place")
    _move(pe, "p2")
    assert pe.exist_predicate(Atom("at", ("r1", "p2")))
    with pytest.raises(KnowledgeError, match=r"unknown object 'p3'"):
        _move(pe, "p3")
