"""A remembered effect of facts hands out the answer and notice sets it prepared
(``FactChange``) when the fact table reports what it expected; they must equal,
in iteration order too, what working them out again gives, and what the general
way (the same effect in a transaction, the logs scanned) gives."""

from __future__ import annotations

from unittest.mock import patch

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.knowledge.applying import FactChange
from plansys_bridge.knowledge.changes import AppliedEffect, KnowledgeChange
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import AddEffect, AndEffect, Atom, DeleteEffect
from plansys_bridge.pddl.parser import parse_domain

DOMAIN = parse_domain(
    """(define (domain d) (:requirements :typing)
      (:types thing)
      (:predicates (p ?x - thing) (q ?x ?y - thing)))""",
    "<d>",
)
ATOMS = [Atom("p", (x,)) for x in "abc"] + [Atom("q", (x, y)) for x in "abc" for y in "abc"]

_PARTS = st.lists(st.tuples(st.booleans(), st.sampled_from(ATOMS)), max_size=10)
"""An effect's parts, repeats and a fact both deleted and added included."""


def _effect(parts: list[tuple[bool, Atom]]) -> AndEffect:
    return AndEffect(tuple(AddEffect(a) if add else DeleteEffect(a) for add, a in parts))


def _knowledge(initial: list[Atom]) -> tuple[ProblemExpert, list[KnowledgeChange]]:
    k = ProblemExpert(DOMAIN)
    for name in "abc":
        k.add_instance(name, "thing")
    for atom in initial:
        k.add_predicate(atom)
    seen: list[KnowledgeChange] = []
    k.subscribe(seen.append)
    return k, seen


def _notices(seen: list[KnowledgeChange], reason: str = "") -> list[tuple[object, ...]]:
    """Each notice as compared: its sets as lists (subscribers may publish them in
    their iteration order); ``reason`` in place of the notice's own when given."""
    return [
        (c.version, reason or c.reason, list(c.added_facts), list(c.removed_facts), c.state)
        for c in seen
    ]


@settings(max_examples=200, deadline=None)
@given(
    initial=st.lists(st.sampled_from(ATOMS), unique=True),
    pool=st.lists(_PARTS, min_size=1, max_size=4),
    order=st.lists(st.integers(0, 3), max_size=12),
)
def test_prepared_answers_equal_worked_out_ones(
    initial: list[Atom], pool: list[list[tuple[bool, Atom]]], order: list[int]
) -> None:
    """Three knowledge bases apply the same effect objects in the same order: one
    remembers them (prepared answers), one remembers none (the limit set to 0:
    worked out every time), one applies them in transactions (the general way)."""
    effects = [_effect(parts) for parts in pool]
    kept, kept_seen = _knowledge(initial)
    fresh, fresh_seen = _knowledge(initial)
    general, general_seen = _knowledge(initial)
    for i in order:
        effect = effects[i % len(effects)]
        answer = kept.apply(effect)
        with patch("plansys_bridge.knowledge.applying._APPLIED_LIMIT", 0):
            again = fresh.apply(effect)
        with general.transaction():
            reference = general.apply(effect)
        assert answer == again == reference
        assert type(answer) is AppliedEffect
        assert [list(x) for x in answer] == [list(x) for x in again]
    assert kept.get_predicates() == fresh.get_predicates() == general.get_predicates()
    assert kept.state() == fresh.state() == general.state()
    # the index's order too (predicates() lists it): a new predicate goes last
    assert list(kept.state().predicates()) == list(general.state().predicates())
    assert _notices(kept_seen) == _notices(fresh_seen)
    assert all(c.reason == "apply" for c in kept_seen)
    assert all(c.reason == "transaction" for c in general_seen)
    assert _notices(kept_seen, "-") == _notices(general_seen, "-")


def test_the_prepared_answer_is_handed_out_in_the_usual_case() -> None:
    """Guards the comparison above: a ground action's effects applied back and
    forth (every delete there, no add there) get the very objects prepared."""
    k, seen = _knowledge([Atom("p", ("a",))])
    there = AndEffect((DeleteEffect(Atom("p", ("a",))), AddEffect(Atom("p", ("b",)))))
    back = AndEffect((DeleteEffect(Atom("p", ("b",))), AddEffect(Atom("p", ("a",)))))
    first = [k.apply(there), k.apply(back)]
    second = [k.apply(there), k.apply(back)]
    assert first[0] is second[0] and first[1] is second[1]
    assert first[0] == ((Atom("p", ("b",)),), (Atom("p", ("a",)),), ())
    assert seen[0].added_facts is seen[2].added_facts
    assert seen[0].removed_facts is seen[2].removed_facts
    # not the usual case (b is there already): worked out, not the prepared answer
    k.add_predicate(Atom("p", ("b",)))
    odd = k.apply(there)
    assert odd == ((), (Atom("p", ("a",)),), ()) and odd is not first[0]


@given(parts=_PARTS)
def test_a_prepared_change_nets_out_a_fact_deleted_and_added_again(
    parts: list[tuple[bool, Atom]],
) -> None:
    deletes = [a for add, a in parts if not add]
    adds = [a for add, a in parts if add]
    prepared = FactChange(_effect(parts), deletes, adds)
    both = set(deletes) & set(adds)
    assert list(prepared.applied.deleted) == [a for a in dict.fromkeys(deletes) if a not in both]
    assert list(prepared.applied.added) == [a for a in dict.fromkeys(adds) if a not in both]
    assert prepared.removed_facts == set(prepared.applied.deleted)
    assert prepared.added_facts == set(prepared.applied.added)


def test_prepared_sets_iterate_as_worked_out_ones_for_many_facts() -> None:
    """Five to seven facts: a set built from a list is sized differently from one
    built from a dict, so its order would differ; the prepared sets keep the order
    the general way's notice has."""
    many = [Atom("q", (x, y)) for x in "abc" for y in "abc"][:6]
    on = AndEffect(tuple(AddEffect(a) for a in many))
    off = AndEffect(tuple(DeleteEffect(a) for a in many))
    kept, kept_seen = _knowledge([])
    general, general_seen = _knowledge([])
    for effect in (on, off, on, off):
        kept.apply(effect)
        with general.transaction():
            general.apply(effect)
    assert _notices(kept_seen, "-") == _notices(general_seen, "-")
    assert kept_seen[0].added_facts is kept_seen[2].added_facts  # prepared, handed out again
