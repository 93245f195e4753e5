"""JournaledTable: undo gives back contents and insertion order; changes are net."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.knowledge.journal import JournaledTable

_KEYS = st.sampled_from("abcdef")
_OPS = st.lists(st.tuples(st.sampled_from(["set", "discard", "clear"]), _KEYS, st.integers(0, 3)))


def _run(table: JournaledTable[str, int], ops: list[tuple[str, str, int]]) -> None:
    for op, key, value in ops:
        if op == "set":
            table.set(key, value)
        elif op == "discard":
            table.discard(key)
        elif value == 0:  # clear now and then, not every third step
            table.clear()


@given(before=_OPS, inside=_OPS)
def test_undo_restores_contents_and_order(
    before: list[tuple[str, str, int]], inside: list[tuple[str, str, int]]
) -> None:
    table: JournaledTable[str, int] = JournaledTable()
    _run(table, before)
    start = list(table.items())
    mark = table.mark()
    _run(table, inside)
    table.undo(mark)
    assert list(table.items()) == start


@given(before=_OPS, inside=_OPS)
def test_changes_since_is_the_net_difference(
    before: list[tuple[str, str, int]], inside: list[tuple[str, str, int]]
) -> None:
    table: JournaledTable[str, int] = JournaledTable()
    _run(table, before)
    old = dict(table)
    table.forget_log()
    mark = table.mark()
    _run(table, inside)
    new = dict(table)
    now, was = table.changes_since(mark)
    assert now == {k: v for k, v in new.items() if old.get(k) != v}
    assert was == {k: v for k, v in old.items() if new.get(k) != v}


def test_order_after_delete_and_set_again_is_the_new_one() -> None:
    table: JournaledTable[str, int] = JournaledTable()
    for key in "abc":
        table.set(key, 1)
    table.delete("a")
    table.set("a", 2)
    assert list(table.items()) == [("b", 1), ("c", 1), ("a", 2)]
