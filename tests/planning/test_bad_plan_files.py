"""Plan files with bad lines: the error names file:line:col of the offending part."""

from __future__ import annotations

import pytest

from plansys_bridge.planning.plan import PlanFormatError, parse_plan


@pytest.mark.parametrize(
    ("text", "where", "words"),
    [
        ("0.000: (move r a b)  [5]\nthis is junk\n", "p.plan:2:1", "expected 'TIME: (action"),
        ("0.000: (move r a b)  [5]\n  1.0:   ( )  [5]\n", "p.plan:2:10", "not an action: '( )'"),
        ("0.000: (move r a b)  [1e999]\n", "p.plan:1:23", "number 1e999 is out of range"),
        ("1e999: (move r a b)  [5]\n", "p.plan:1:1", "number 1e999 is out of range"),
    ],
)
def test_bad_plan_line_names_its_place(text: str, where: str, words: str) -> None:
    with pytest.raises(PlanFormatError) as info:
        parse_plan(text, "p.plan")
    assert str(info.value.location) == where
    assert words in str(info.value)
