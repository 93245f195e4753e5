"""The order of a plan's happenings and the reduction of the orderings between them.

Happenings are ints: ``2*step`` is a step's start, ``2*step+1`` its end. They are
sorted by time (ends before starts at the same time, as a temporal plan means),
and the orderings found between them are reduced to those a reader needs.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import repeat
from operator import add, itemgetter

from plansys_bridge.planning.orderings import END, START, Point
from plansys_bridge.planning.plan import PlanStep

__all__ = ["happening_order", "point_of", "transitive_reduction"]


def happening_order(steps: Sequence[PlanStep]) -> list[int]:
    """Every happening of ``steps`` in the order the plan makes them happen: by time
    (rounded to the microsecond), ends of actions with a duration first, then by
    step, starts before ends. The keys are made in two comprehensions, without a
    key call (or an append) per happening; the times are rounded by ``map`` (no
    bytecode per time), each distinct one once, and a happening is its key's last
    item (``2*step+point`` orders as ``(step, point)``)."""
    times = [step.time for step in steps]
    durations = [step.duration for step in steps]
    ends = list(map(add, times, durations))
    # Each distinct time rounded once: ``round(t, 6)`` is a correctly rounded decimal
    # (about half a microsecond a time), and the steps of a plan share few times
    # (those running together start and end together).
    distinct = {*times, *ends}
    rounded = dict(zip(distinct, map(round, distinct, repeat(6)), strict=True)).__getitem__
    starts = list(map(rounded, times))
    ends = list(map(rounded, ends))
    keys = [(start, 1, 2 * i) for i, start in enumerate(starts)]
    keys += [
        (starts[i], 1, 2 * i + 1) if duration <= 0 else (ends[i], 0, 2 * i + 1)
        for i, duration in enumerate(durations)
    ]
    keys.sort()
    return list(map(itemgetter(2), keys))


def point_of(h: int) -> Point:
    """Whether happening ``h`` is its step's start or its end."""
    return END if h % 2 else START


def transitive_reduction(
    order: Sequence[int], succ: Sequence[Sequence[int]], pos: Sequence[int]
) -> list[tuple[int, int]]:
    """Drop every edge implied by a longer path; each action's start->end is implicit.

    ``succ`` lists each happening's edge targets, ``pos`` each happening's plan
    position; every edge points forward in ``order``. Reachability is kept as
    Python integers used as bit sets over plan positions, so a 5,000-action plan
    (10,000 happenings) reduces in well under a second.
    """
    reach = [0] * len(pos)
    kept: list[tuple[int, int]] = []
    for h in reversed(order):
        targets = succ[h]
        covered = 0
        for t in targets:
            covered |= reach[t]
        if h & 1:
            mine = covered
        else:  # a start reaches its own end
            covered |= reach[h + 1]
            mine = covered | 1 << pos[h + 1]
        for t in targets:
            bit = 1 << pos[t]
            mine |= bit
            if not covered & bit:
                kept.append((h, t))
        reach[h] = mine
    return kept
