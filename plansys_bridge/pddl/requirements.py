"""PDDL requirement names: the known ones, what each implies, and where one is written.

Why apart from the checks: the requirement list is data the checks, the planner's
feature detection and error messages all read; it changes when PDDL grows, not
when a check does.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from plansys_bridge.errors import SourceLocation

__all__ = ["KNOWN_REQUIREMENTS", "expand_requirements", "requirement_loc"]

KNOWN_REQUIREMENTS = frozenset(
    {
        ":strips",
        ":typing",
        ":negative-preconditions",
        ":disjunctive-preconditions",
        ":equality",
        ":existential-preconditions",
        ":universal-preconditions",
        ":quantified-preconditions",
        ":conditional-effects",
        ":fluents",
        ":numeric-fluents",
        ":object-fluents",
        ":adl",
        ":durative-actions",
        ":duration-inequalities",
        ":continuous-effects",
        ":derived-predicates",
        ":timed-initial-literals",
        ":preferences",
        ":constraints",
        ":action-costs",
        ":time",
    }
)

_IMPLIES = {
    ":adl": (
        ":strips",
        ":typing",
        ":negative-preconditions",
        ":disjunctive-preconditions",
        ":equality",
        ":quantified-preconditions",
        ":conditional-effects",
    ),
    ":quantified-preconditions": (":existential-preconditions", ":universal-preconditions"),
    ":fluents": (":numeric-fluents", ":object-fluents"),
    ":action-costs": (":numeric-fluents",),
}


def expand_requirements(requirements: tuple[str, ...] | list[str]) -> frozenset[str]:
    """The requirement set with implied requirements (``:adl`` -> ...) added."""
    out: set[str] = set()
    stack = list(requirements)
    while stack:
        req = stack.pop()
        if req not in out:
            out.add(req)
            stack.extend(_IMPLIES.get(req, ()))
    return frozenset(out)


def requirement_loc(
    req: str, file: str | None, sources: Mapping[str, str]
) -> SourceLocation | None:
    """Where ``req`` is first written in ``file`` (``a.pddl:b.pddl`` for merged domains)."""
    if file is None:
        return None
    for name in file.split(":") if file not in sources else [file]:
        text = sources.get(name)
        if text is None:
            continue
        match = re.search(re.escape(req) + r"(?![a-z0-9_\-])", text.lower())
        if match:
            line = text.count("\n", 0, match.start()) + 1
            col = match.start() - (text.rfind("\n", 0, match.start()) + 1) + 1
            return SourceLocation(name, line, col)
    return None
