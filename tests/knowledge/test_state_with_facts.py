"""State.with_facts (an effect's few facts, edited fact by fact) gives the state
State.with_changes gives, and hands back the same snapshot when nothing moves."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.knowledge import state as state_module
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Atom

FACTS = [Atom("p", (x,)) for x in "abc"] + [Atom("q", (x, y)) for x in "ab" for y in "ab"]
_SOME = st.lists(st.sampled_from(FACTS), max_size=6)


@given(before=_SOME, deletes=_SOME, adds=_SOME)
def test_with_facts_is_with_changes(
    before: list[Atom], deletes: list[Atom], adds: list[Atom]
) -> None:
    start = State(before, {("level", ("a",)): 1.0}, {"a": "thing"})
    short = start.with_facts(deletes, adds)
    general = start.with_changes(adds=adds, deletes=deletes)
    assert short == general and short.facts == general.facts
    assert list(short.predicates()) == list(general.predicates())
    assert (short is start) == (general is start)
    assert short.same_fluents(start) and short.same_objects(start)


def test_small_changes_take_the_short_way() -> None:
    """Guards the comparison above: most of its examples are below the bound."""
    assert state_module._FEW >= 4
