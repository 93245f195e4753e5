"""What several benchmarks share: where the shared data is, latency summaries, and a
performer that stamps when it starts and finishes.

Benchmarks import it as a sibling module (``python benchmarks/<name>.py`` puts this
folder on the import path).
"""

from __future__ import annotations

import asyncio
import os
import statistics
import time
from pathlib import Path
from typing import Any

from plansys_bridge.performers.base import ActionGoal, ActionPerformer

SHARED = Path(__file__).resolve().parents[2] / "shared"
"""shared/ beside the repository: the larger real bags."""

FIXTURES = Path(
    os.environ.get("PLANSYS_BRIDGE_FIXTURES")
    or Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "plansys2"
)
"""PlanSys2's PDDL corpus (``$PLANSYS_BRIDGE_FIXTURES`` overrides, as in the tests)."""

BAGS = SHARED / "bags"


def percentile(values: list[float], q: float) -> float:
    """The ``q`` quantile (0..1) of ``values``: the nearest sample at or above it."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def summary(samples_s: list[float]) -> dict[str, float]:
    """Count, median, p90, p99 and max of samples in seconds, in microseconds."""
    us = [s * 1e6 for s in samples_s]
    return {
        "n": len(us),
        "median_us": statistics.median(us),
        "p90_us": percentile(us, 0.90),
        "p99_us": percentile(us, 0.99),
        "max_us": max(us),
    }


class StampingPerformer(ActionPerformer):
    """Works for ``work_s`` real seconds (0: yields once, so the client settles into
    waiting as with a real action); stamps, per request id, ``execute()`` starting
    and FINISH being sent (``time.perf_counter``)."""

    work_s = 0.0

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.started: dict[str, float] = {}
        self.finished: dict[str, float] = {}

    async def execute(self, goal: ActionGoal) -> str | None:
        self.started[goal.request_id] = time.perf_counter()
        await asyncio.sleep(self.work_s)
        return None

    def _finish(self, goal: ActionGoal, success: bool, status: str) -> None:
        self.finished[goal.request_id] = time.perf_counter()
        super()._finish(goal, success, status)
