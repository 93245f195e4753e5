"""The contextual lexer: keywords only where the parser accepts them, exact
positions across comments and multi-line keywords, no pathological slowness."""

from __future__ import annotations

import pytest

from plansys_bridge.errors import PddlSemanticError, PddlSyntaxError
from plansys_bridge.pddl.model import Atom, DurativeAction
from plansys_bridge.pddl.parser import _parser, parse_atom, parse_domain, parse_problem


def test_no_parser_state_mixes_terms_with_names_or_variables() -> None:
    # The lexer turns names and variables into TERMs wherever a TERM is accepted;
    # that is only right if no state also accepts a plain NAME or VARIABLE.
    states = _parser().parser.parser.parser.parse_table.states
    assert states
    for actions in states.values():
        assert not ("TERM" in actions and ("NAME" in actions or "VARIABLE" in actions))


def test_keywords_are_names_where_a_name_is_expected() -> None:
    domain = parse_domain(
        """(define (domain kw) (:requirements :typing :durative-actions)
  (:types start end - object)
  (:constants and all - end)
  (:predicates (at ?x - start ?y - end) (over ?x - end))
  (:durative-action at :parameters (?s - start)
    :duration (= ?duration 1)
    :condition (and (at start (at ?s and)) (over
                  all (over all)))
    :effect (at end (not (at ?s and)))))"""
    )
    action = domain.actions[0]
    assert isinstance(action, DurativeAction) and action.name == "at"
    assert action.at_start == Atom("at", ("?s", "and"))
    assert action.over_all == Atom("over", ("all",))
    assert parse_atom("(at start end)") == Atom("at", ("start", "end"))


def test_positions_after_comments_and_multiline_keywords() -> None:
    text = """(define (domain pos) (:requirements :durative-actions)
  ; a comment with ( parentheses ) and ;;;; semicolons
  (:predicates (p) (q))
  (:durative-action a :parameters () :duration (= ?duration 1)
    :condition (at
        start (p))
    :effect (at end (r))))"""
    with pytest.raises(PddlSemanticError) as info:
        parse_domain(text, "pos.pddl")
    loc = info.value.location
    assert loc is not None
    assert (loc.line, loc.column) == (7, 22)  # the unknown predicate r


def test_many_comment_characters_do_not_stall() -> None:
    comments = (";" * 3000 + "\n") * 20
    with pytest.raises(PddlSyntaxError) as info:
        parse_problem("(define (problem p)\n" + comments + " (:init (p)) @")
    assert info.value.location is not None and info.value.location.line == 22
    assert "'@'" in info.value.message
