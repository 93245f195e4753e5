"""JournaledTable.exchange (a prepared change's keys, in the case it is made for)
does what swap does in that case, and refuses, changing nothing, in any other."""

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
    table.forget_log()
    return table


def _prepared(gone: list[str], came: list[str]) -> tuple[tuple[str, ...], ...]:
    """(gone, came, fresh) as a prepared change holds them: no repeats, and the
    keys that come without going."""
    went, come = tuple(dict.fromkeys(gone)), tuple(dict.fromkeys(came))
    return went, come, tuple(k for k in come if k not in went)


@given(before=_KEYS, gone=_KEYS, came=_KEYS, value=st.integers(0, 2))
def test_exchange_is_swap_in_the_usual_case_and_nothing_else(
    before: list[str], gone: list[str], came: list[str], value: int
) -> None:
    exchanged, swapped = _table(before), _table(before)
    start, writes = list(exchanged.items()), exchanged.writes
    went, come, fresh = _prepared(gone, came)
    usual = all(k in exchanged for k in went) and not any(k in exchanged for k in fresh)
    assert exchanged.exchange(went, come, fresh, value) is usual
    if not usual:
        assert list(exchanged.items()) == start and exchanged.writes == writes
        return
    assert swapped.swap(went, come, value) == (dict.fromkeys(went), dict.fromkeys(come))
    assert list(exchanged.items()) == list(swapped.items())
    assert exchanged.writes == swapped.writes and exchanged.mark() == 0
    # and later changes see the same insertion places (an undo puts keys back there)
    for table in (exchanged, swapped):
        mark = table.mark()
        table.discard_many("abcdef")
        table.undo(mark)
    assert list(exchanged.items()) == list(swapped.items())


def test_exchange_is_taken_in_a_usual_case() -> None:
    """Guards the comparison above: it sees both answers."""
    table = _table(["a", "b"])
    assert table.exchange(("a",), ("a", "c"), ("c",), 5)
    assert list(table.items()) == [("b", 1), ("a", 5), ("c", 5)]
    assert not table.exchange(("a",), ("b",), ("b",), 5)


class _Breaks(tuple[str, ...]):
    """Keys whose iteration fails at key ``after`` (the table has checked them and
    is changing itself)."""

    after = 0

    def __iter__(self) -> Iterator[str]:
        for i, key in enumerate(tuple.__iter__(self)):
            if i == self.after:
                raise RuntimeError("broken half way")
            yield key


@given(before=_KEYS, gone=_KEYS, came=_KEYS, where=st.integers(0, 6), in_came=st.booleans())
def test_an_exchange_failing_half_way_leaves_the_table_as_it_was(
    before: list[str], gone: list[str], came: list[str], where: int, in_came: bool
) -> None:
    went, come, fresh = _prepared(gone, came)
    broken = _Breaks(come if in_came else went)
    broken.after = where
    table, fresh_copy = _table(before), _table(before)
    start = list(table.items())
    usual = all(k in table for k in went) and not any(k in table for k in fresh)
    if not usual or where >= len(broken):
        return
    with pytest.raises(RuntimeError, match="broken half way"):
        if in_came:
            table.exchange(went, broken, fresh, 7)
        else:
            # the check reads ``gone`` first: break only the second pass
            table.exchange(_SecondPass(broken), come, fresh, 7)
    assert list(table.items()) == start and table.mark() == 0
    assert table.exchange(went, come, fresh, 7) and fresh_copy.exchange(went, come, fresh, 7)
    assert list(table.items()) == list(fresh_copy.items())


class _SecondPass(tuple[str, ...]):
    """Iterates as a plain tuple once, then as the broken keys it was made of."""

    def __new__(cls, broken: _Breaks) -> _SecondPass:
        made = super().__new__(cls, tuple.__iter__(broken))
        made.broken = broken
        made.passes = 0
        return made

    broken: _Breaks
    passes: int

    def __iter__(self) -> Iterator[str]:
        self.passes += 1
        return iter(self.broken) if self.passes > 1 else tuple.__iter__(self)
