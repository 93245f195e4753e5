"""State snapshots: copy-on-write changes agree with building a state from scratch."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.knowledge.state import FluentKey, State
from plansys_bridge.pddl.model import Atom

NAMES = ["a", "b", "c"]
atoms = st.builds(
    Atom,
    st.sampled_from(["p", "q", "r"]),
    st.tuples(st.sampled_from(NAMES), st.sampled_from(NAMES)),
)
keys = st.tuples(st.sampled_from(["f", "g"]), st.tuples(st.sampled_from(NAMES)))
values = st.dictionaries(keys, st.integers(-5, 5).map(float), max_size=5)


@settings(max_examples=120, deadline=None)
@given(
    facts=st.sets(atoms, max_size=10),
    fluents=values,
    adds=st.sets(atoms, max_size=6),
    deletes=st.sets(atoms, max_size=6),
    updates=values,
    removed=st.sets(keys, max_size=3),
)
def test_with_changes_matches_a_fresh_state(
    facts: set[Atom],
    fluents: dict[FluentKey, float],
    adds: set[Atom],
    deletes: set[Atom],
    updates: dict[FluentKey, float],
    removed: set[FluentKey],
) -> None:
    before = State(facts, fluents, {n: "object" for n in NAMES})
    after = before.with_changes(adds, deletes, updates, removed)
    expected_fluents = {k: v for k, v in fluents.items() if k not in removed} | updates
    assert after == State((facts - deletes) | adds, expected_fluents, {n: "object" for n in NAMES})
    assert after.facts == (facts - deletes) | adds
    assert dict(after.fluents) == expected_fluents
    for key in {*fluents, *updates, *removed}:
        assert after.value(*key) == expected_fluents.get(key)
    # the old snapshot is untouched
    assert before.facts == facts and dict(before.fluents) == fluents


def test_unchanged_tables_are_shared() -> None:
    s = State([Atom("p", ("a",))], {("f", ("a",)): 1.0}, {"a": "object"})
    assert s.with_changes() is s
    assert s.with_changes(adds=[Atom("p", ("a",))]) is s  # already true
    t = s.with_changes(adds=[Atom("q", ("a",))])
    assert t.same_fluents(s) and t.same_objects(s) and t.tuples("p") is s.tuples("p")
    u = t.with_changes(fluents={("f", ("a",)): 2.0})
    assert not u.same_fluents(t) and u.value("f", ("a",)) == 2.0 and t.value("f", ("a",)) == 1.0
    v = u.with_changes(objects={"a": "object", "b": "object"})
    assert not v.same_objects(u) and v.objects == {"a": "object", "b": "object"}
    assert len(v) == 2 and Atom("q", ("a",)) in v and "q" in set(v.predicates())


class _Lookalike:
    """Not an atom, though it has an atom's fields."""

    def __init__(self, atom: Atom) -> None:
        self.predicate, self.args = atom.predicate, atom.args


@given(facts=st.sets(atoms, max_size=8), asked=atoms)
def test_membership_is_membership_in_the_facts(facts: set[Atom], asked: Atom) -> None:
    state = State(facts)
    assert (asked in state) == (asked in state.facts) == (asked in facts)
    assert _Lookalike(asked) not in state and (asked.predicate, asked.args) not in state
    assert None not in state and "p" not in state


def test_each_snapshot_has_a_cache_of_its_own_made_when_asked() -> None:
    """Made on first use, then the same dict; a new snapshot (either way of making
    one) starts without the old one's entries."""
    start = State([Atom("p", ("a",))])
    start.cache()["k"] = 1
    assert start.cache() is start.cache() and start.cache() == {"k": 1}
    for after in (
        start.with_facts([], [Atom("p", ("b",))]),
        start.with_changes(adds=[Atom("p", ("b",))]),
    ):
        assert after.cache() == {} and after.cache() is not start.cache()
