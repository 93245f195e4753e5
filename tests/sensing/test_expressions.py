"""The rule language through the real lark grammar: what it computes, what it refuses."""

from __future__ import annotations

import re

import pytest

from plansys_bridge.sensing.expressions import ExpressionError, parse_expression


@pytest.mark.parametrize(
    ("text", "sample", "expected"),
    [
        ("battery_remaining < 25", {"battery_remaining": 20}, True),
        ("battery_remaining < 25", {"battery_remaining": 25}, False),
        ("a < 1 or b > 2 and c", {"a": 5, "b": 3, "c": 0}, False),  # and binds tighter
        ("(a < 1 or b > 2) and not c", {"a": 5, "b": 3, "c": 0}, True),
        ("not not x", {"x": 7}, True),
        ("voltages[1] / 1000 >= 11.1", {"voltages[1]": 11100}, True),
        ("pose.position.x - -1.5 == 2", {"pose.position.x": 0.5}, True),
        ("2 + 3 * 4 % 5 - -1", {}, 2 + (3 * 4) % 5 + 1),
        ("mode == 'RTL'", {"mode": "RTL"}, True),
        ('mode != "GUIDED"', {"mode": "GUIDED"}, False),
        ("armed == true", {"armed": True}, True),
        ("1e2 > 99.5", {}, True),
        ("name == 'x'", {"name": b"x\0\0"}, True),  # MAVLink char arrays arrive as bytes
    ],
)
def test_values(text: str, sample: dict[str, object], expected: object) -> None:
    assert parse_expression(text).value(sample) == expected


def test_fields_read_are_listed() -> None:
    expr = parse_expression("a.b[2] < 3 and not (c + d.e) or f == 'g'")
    assert expr.fields == {"a.b[2]", "c", "d.e", "f"}
    # keywords are whole words only: fields may begin with them
    assert parse_expression("notice and order or android").fields == {
        "notice",
        "order",
        "android",
    }


@pytest.mark.parametrize(
    ("text", "column", "words"),
    [
        ("a < b < c", 7, "unexpected '<'"),
        ("a +", 4, "unexpected the end of the text"),
        ("a @ b", 3, "unexpected '@'"),
        ("(a", 3, "expected ')'"),
        ("__import__('os').system('x')", 11, "unexpected '('"),
        ("a.b()", 4, "unexpected '('"),
        ("1e999 > a", 1, "not a finite number"),
        ("a = 1", 3, "unexpected '='"),
    ],
)
def test_what_is_not_an_expression_names_the_column(text: str, column: int, words: str) -> None:
    with pytest.raises(ExpressionError) as info:
        parse_expression(text)
    assert info.value.column == column, info.value
    assert words in str(info.value)


@pytest.mark.parametrize(
    ("text", "sample", "words"),
    [
        ("a / b > 1", {"a": 1, "b": 0}, "division by zero"),
        ("a < 'x'", {"a": 1}, "'<' needs numbers"),
        ("missing > 1", {}, "no field 'missing'"),
        ("a + 1 > 0", {"a": "text"}, "'+' needs numbers"),
    ],
)
def test_values_it_cannot_compute_are_errors(
    text: str, sample: dict[str, object], words: str
) -> None:
    with pytest.raises(ExpressionError, match=re.escape(words)):
        parse_expression(text).value(sample)


def test_numbers_for_functions() -> None:
    assert parse_expression("current_battery / 100").number({"current_battery": 250}) == 2.5
    assert parse_expression("a > 1").number({"a": 2}) == 1.0
    with pytest.raises(ExpressionError, match="not a finite number"):
        parse_expression("mode").number({"mode": "RTL"})
