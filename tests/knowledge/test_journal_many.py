"""JournaledTable.set_many / discard_many: the same table, log and undo as one
set or discard per key, and they report the keys that came and went, in order."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.knowledge.journal import JournaledTable

_KEYS = st.lists(st.sampled_from("abcdef"), max_size=8)


def _table(keys: list[str]) -> JournaledTable[str, int]:
    table: JournaledTable[str, int] = JournaledTable()
    for i, key in enumerate(keys):
        table.set(key, i)
    return table


@given(before=_KEYS, gone=_KEYS, came=_KEYS, value=st.integers(0, 2))
def test_many_at_once_is_one_at_a_time(
    before: list[str], gone: list[str], came: list[str], value: int
) -> None:
    many, single = _table(before), _table(before)
    start = list(many.items())
    mark = many.mark()
    present = set(many)
    removed = many.discard_many(gone)
    assert list(removed) == [k for k in dict.fromkeys(gone) if k in present]
    present -= set(removed)
    new = many.set_many(came, value)
    assert list(new) == [k for k in dict.fromkeys(came) if k not in present]
    for key in gone:
        single.discard(key)
    for key in came:
        single.set(key, value)
    assert list(many.items()) == list(single.items()) and many.writes == single.writes
    assert many.changes_since(mark) == single.changes_since(mark)
    many.undo(mark)
    assert list(many.items()) == start


@given(before=_KEYS, gone=_KEYS, came=_KEYS)
def test_swap_is_both_in_turn_and_leaves_no_log(
    before: list[str], gone: list[str], came: list[str]
) -> None:
    swapped, stepped = _table(before), _table(before)
    swapped.forget_log()
    assert swapped.swap(gone, came, 7) == (stepped.discard_many(gone), stepped.set_many(came, 7))
    assert list(swapped.items()) == list(stepped.items())
    assert swapped.mark() == 0 and swapped.writes == stepped.writes


def test_a_swap_that_fails_half_way_puts_everything_back() -> None:
    table = _table(["a", "b", "c"])
    start = list(table.items())
    mark = table.mark()

    class Broken(list[str]):
        def __iter__(self) -> Iterator[str]:
            yield "d"
            raise RuntimeError("broken iterator")

    with pytest.raises(RuntimeError, match="broken iterator"):
        table.swap(["a", "c"], Broken(["d", "e"]), 9)
    assert list(table.items()) == start and table.mark() == mark


class _Breaks(list[str]):
    """A list whose iteration fails after ``after`` keys."""

    def __init__(self, keys: list[str], after: int) -> None:
        super().__init__(keys)
        self.after = after

    def __iter__(self) -> Iterator[str]:
        for i, key in enumerate(list.__iter__(self)):
            if i == self.after:
                raise RuntimeError("broken half way")
            yield key


@given(
    before=_KEYS,
    gone=_KEYS,
    came=_KEYS,
    where=st.integers(0, 8),
    in_came=st.booleans(),
    value=st.integers(0, 2),
)
def test_a_swap_failing_anywhere_leaves_the_table_as_it_was(
    before: list[str], gone: list[str], came: list[str], where: int, in_came: bool, value: int
) -> None:
    table = _table(before)
    table.forget_log()
    start = list(table.items())
    broken_gone = gone if in_came else _Breaks(gone, where)
    broken_came = _Breaks(came, where) if in_came else came
    if where >= len(broken_came if in_came else broken_gone):
        table.swap(broken_gone, broken_came, value)  # never breaks: a plain swap
        return
    with pytest.raises(RuntimeError, match="broken half way"):
        table.swap(broken_gone, broken_came, value)
    assert list(table.items()) == start and table.mark() == 0
    # and the table still works as one: the same as a fresh copy after a swap
    fresh = _table(before)
    assert table.swap(gone, came, value) == fresh.swap(gone, came, value)
    assert list(table.items()) == list(fresh.items())
