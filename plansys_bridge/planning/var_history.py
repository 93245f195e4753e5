"""What the plan graph builder keeps per variable while it simulates a plan.

A variable (a ground atom or a numeric fluent) has a history of accesses, grouped
in runs of accesses that commute; :mod:`plansys_bridge.planning.plan_graph` orders
each access after the members of the previous run. The builder works with the
histories themselves rather than the variables, looked up once per fixed access.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TypeAlias

from plansys_bridge.knowledge.state import FluentKey
from plansys_bridge.planning.effect_access import EffectAccess, Var
from plansys_bridge.planning.orderings import Kind

__all__ = ["Access", "VarHistory", "subject_text", "var_text"]


@dataclass(eq=False, slots=True)
class VarHistory:
    """Accesses of one variable, grouped in runs of mutually commuting accesses.

    Hashed by identity: the builder resolves a fixed access's variables to their
    histories once per build, and keys its tables by history, because hashing a
    variable (a tuple holding an atom) on every access was much of a build.
    """

    var: Var
    is_atom: bool
    kind: str | None  # kind of the current run
    current: list[tuple[int, Kind | None]] = field(default_factory=list)
    """(tail happening, access role) of the current run's members."""
    previous: list[tuple[int, Kind | None]] = field(default_factory=list)
    latest_effect: int | None = None
    changeable: bool = True
    """Whether some action of the plan may change the variable (the builder watches
    only such variables for over-all requirements an effect breaks)."""
    text: str | None = None
    """:func:`var_text` of ``var``, written the first time an ordering needs it."""
    value: bool = False
    """An atom's truth where the simulation has got to: the builder checks
    conditions of literals and applies plain effects on these values, and brings
    its :class:`~plansys_bridge.knowledge.state.State` up to date only when the
    evaluator needs one."""


Access: TypeAlias = tuple[
    EffectAccess,
    tuple[VarHistory, ...],
    tuple[tuple[VarHistory, str], ...],
    tuple[VarHistory, ...],
    tuple[VarHistory, ...],
    tuple[VarHistory, ...],
]
"""An effect's accesses with the histories it reads, writes (and how) and changes,
and the histories of the atoms it adds and of those it deletes (and does not add)."""


def subject_text(hist: VarHistory) -> str:
    """What an ordering on ``hist`` protects, as the orderings write it (written
    once per variable: many orderings protect the same one)."""
    text = hist.text
    if text is None:
        text = hist.text = var_text(hist.var)
    return text


def var_text(var: Var) -> str:
    """``(robot_at r1 kitchen)`` for an atom or a fluent."""
    if var[0] == "a":
        return str(var[1])
    key: FluentKey = var[1]  # type: ignore[assignment]
    return "(" + " ".join((key[0], *key[1])) + ")"
