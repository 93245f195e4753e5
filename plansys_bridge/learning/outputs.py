"""What learning writes: duration functions for the planner, bid costs for auctions.

**Functions file.** A domain whose durations are numeric functions of the action's
parameters (``:duration (= ?duration (move_time ?r ?from ?to))``) is planned with
whatever values the problem gives those functions. For each such action the runs
are grouped by the function's ground arguments and the median written as a problem
init entry, ``(= (move_time robot1 hall kitchen) 4.2)``, with a comment giving the
spread it rests on. A mission loads the file with ``knowledge.function_files`` (on
top of its guesses: only what was observed is overwritten). Actions whose duration
is a constant, or an expression that is not one function, cannot be learned this
way; they are listed as notes.

**Bid costs.** Per performer, the expected seconds per success of each action
(median over success rate), by action name and by ground action: a YAML file the
mission names with ``bid_costs:``, so a best-bid auction gives each action to the
performer that has done it fastest and most reliably.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import yaml

from plansys_bridge.learning.runs import ActionRun, Learned, stats_of
from plansys_bridge.learning.stats import DurationStats
from plansys_bridge.pddl.model import Domain, DurativeAction, FluentRef, Number
from plansys_bridge.pddl.writer import write_number

__all__ = [
    "FunctionEstimate",
    "bid_costs",
    "bid_costs_text",
    "duration_functions",
    "functions_text",
]


@dataclass(frozen=True)
class FunctionEstimate:
    fluent: str
    """Ground function text, ``(move_time robot1 hall kitchen)``."""
    action: str
    stats: DurationStats
    observed: bool = True
    """False: not observed itself, given the median of all runs of its action."""

    @property
    def entry(self) -> str:
        return f"(= {self.fluent} {write_number(round(self.stats.median, 3))})"


def duration_functions(
    domain: Domain, learned: Learned, *, fill: bool = True
) -> tuple[list[FunctionEstimate], list[str]]:
    """Estimates of every ground duration function the runs observed, and notes on
    the learned actions whose durations are not a function of their parameters.

    With ``fill``, the duration functions the recorded missions knew but no run
    observed get the median of all runs of their action: a guess never corrected
    would otherwise make the planner prefer exactly what it knows least about."""
    estimates: list[FunctionEstimate] = []
    notes: list[str] = []
    observed = {r.action for r in learned.runs if r.succeeded}
    for action in domain.actions:
        name = action.name.lower()
        if name not in observed:
            continue
        fluent = _duration_fluent(action) if isinstance(action, DurativeAction) else None
        if fluent is None or not isinstance(action, DurativeAction):
            notes.append(_not_learnable(action))
            continue
        slots = _slots(action, fluent)
        if slots is None:
            notes.append(
                f"{name}: the duration function {fluent.name} takes something other than "
                "the action's parameters; not learned"
            )
            continue
        by_fluent: dict[tuple[str, ...], list[ActionRun]] = {}
        for run in learned.runs:
            if run.action == name:
                args = tuple(run.arguments[s] if isinstance(s, int) else s for s in slots)
                by_fluent.setdefault(args, []).append(run)
        seen = set()
        for args, group in sorted(by_fluent.items()):
            stats = stats_of(group)
            if stats.count:
                text = "(" + " ".join((fluent.name, *args)) + ")"
                estimates.append(FunctionEstimate(text, name, stats))
                seen.add(text)
        if fill:
            overall = stats_of(r for r in learned.runs if r.action == name)
            prefix = f"({fluent.name.lower()} "
            for text in sorted(learned.known - seen):
                if text.startswith(prefix) or text == f"({fluent.name.lower()})":
                    estimates.append(FunctionEstimate(text, name, overall, observed=False))
    return estimates, notes


def _duration_fluent(action: DurativeAction) -> FluentRef | None:
    exact = [c for c in action.duration if c.op == "="]
    if len(exact) == 1 and isinstance(exact[0].value, FluentRef):
        return exact[0].value
    return None


def _not_learnable(action: Any) -> str:
    name = action.name.lower()
    if not isinstance(action, DurativeAction):
        return f"{name}: not a durative action; its duration is not planned"
    exact = [c for c in action.duration if c.op == "="]
    if len(exact) == 1 and isinstance(exact[0].value, Number):
        value = write_number(exact[0].value.value)
        return (
            f"{name}: the domain gives the constant duration {value}; write it as a function "
            f"(:duration (= ?duration (NAME ?params))) to learn it"
        )
    return f"{name}: its duration is not one function of its parameters; not learned"


def _slots(action: DurativeAction, fluent: FluentRef) -> list[int | str] | None:
    """For each argument of ``fluent``: the index of the action parameter it is, or
    the constant it names; None when it is neither."""
    index = {p.name.lower(): i for i, p in enumerate(action.parameters)}
    slots: list[int | str] = []
    for arg in fluent.args:
        text = str(arg).lower()
        if text.startswith("?"):
            if text not in index:
                return None
            slots.append(index[text])
        else:
            slots.append(text)
    return slots


def functions_text(estimates: list[FunctionEstimate], notes: list[str], header: str) -> str:
    """The functions file: one init entry a line, each with the spread it rests on."""
    lines = [f"; {line}" for line in header.splitlines()]
    lines += [f"; note: {n}" for n in notes]
    for e in estimates:
        s = e.stats
        spread = f"n={s.count} IQR {s.iqr:.3f} stdev {s.stdev:.3f} success {s.success_rate:.0%}"
        if not e.observed:
            spread = f"not observed: all {e.action} runs, {spread}"
        lines.append(f"{e.entry}  ; {spread}")
    return "\n".join(lines) + "\n"


def bid_costs(learned: Learned) -> dict[str, dict[str, float]]:
    """performer -> {action name or ground action text -> expected seconds per success}."""
    out: dict[str, dict[str, float]] = {}
    for (performer, action), stats in learned.by_performer().items():
        if performer and math.isfinite(stats.expected_cost()):
            out.setdefault(performer, {})[action] = round(stats.expected_cost(), 3)
    for (performer, (action, args)), stats in learned.by_performer_ground().items():
        if performer and math.isfinite(stats.expected_cost()):
            text = "(" + " ".join((action, *args)) + ")"
            out.setdefault(performer, {})[text] = round(stats.expected_cost(), 3)
    return out


def bid_costs_text(learned: Learned, header: str) -> str:
    comment = "".join(f"# {line}\n" for line in header.splitlines())
    body = yaml.safe_dump({"performers": bid_costs(learned)}, sort_keys=True, width=200)
    return comment + body
