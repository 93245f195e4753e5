"""Grounding arguments: the no-bindings shortcut agrees with the general path."""

from __future__ import annotations

import pytest

from plansys_bridge.knowledge.grounding import UnboundVariableError, ground_args


@pytest.mark.parametrize("args", [(), ("r1",), ("r1", "k", "c-2")])
def test_ground_arguments_come_back_as_they_are(args: tuple[str, ...]) -> None:
    assert ground_args(args, {}) == args == ground_args(args, {"?unused": "x"})
    assert ground_args(args, {}) is args


@pytest.mark.parametrize("bindings", [{}, {"?other": "x"}])
def test_an_unbound_variable_is_named_with_or_without_bindings(bindings: dict[str, str]) -> None:
    with pytest.raises(UnboundVariableError, match=r"variable \?r is not bound"):
        ground_args(("k", "?r"), bindings)


def test_variables_are_replaced_and_a_list_comes_back_a_tuple() -> None:
    assert ground_args(("?r", "k"), {"?r": "r1"}) == ("r1", "k")
    assert ground_args(["r1", "k"], {}) == ("r1", "k")  # type: ignore[arg-type]
