"""Requirements as text a user can act on: the conjuncts that fail, ground.

A failed check names what does not hold (``(robot_at r1 kitchen)``), not the whole
precondition, with the action's arguments in place of its variables.
"""

from __future__ import annotations

from collections.abc import Mapping

from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.formulas import conjuncts
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import Condition

__all__ = ["condition_text", "describe_unmet"]


def describe_unmet(
    evaluator: Evaluator,
    cond: Condition,
    state: State,
    bindings: Mapping[str, str],
    duration: float | None = None,
) -> str:
    """The conjuncts of ``cond`` that do not hold in ``state``, as ground PDDL text
    (the whole condition if it fails as a whole)."""
    failing = [c for c in conjuncts(cond) if not evaluator.holds(c, state, bindings, duration)]
    return " ".join(condition_text(c, bindings) for c in (failing or [cond]))


def condition_text(cond: Condition, bindings: Mapping[str, str]) -> str:
    """``cond`` as PDDL text with ``bindings`` substituted for its variables."""
    from plansys_bridge.pddl.writer import write_condition

    text = write_condition(cond)
    for var, value in sorted(bindings.items(), key=lambda kv: -len(kv[0])):
        text = _replace_var(text, var, value)
    return text


def _replace_var(text: str, var: str, value: str) -> str:
    out: list[str] = []
    i = 0
    n = len(var)
    while True:
        j = text.find(var, i)
        if j < 0:
            out.append(text[i:])
            return "".join(out)
        end = j + n
        if end < len(text) and (text[end].isalnum() or text[end] in "-_"):
            out.append(text[i:end])
        else:
            out.append(text[i:j] + value)
        i = end
