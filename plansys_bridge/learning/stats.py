"""Duration and success statistics of one group of recorded action runs.

Durations are summarised robustly: the median is what a planner should assume (a
few runs stalled by a replan or a slow auction do not drag it), the interquartile
range and the standard deviation say how far to trust it, and the count says how
many runs it rests on. Only runs that succeeded have a duration worth learning; a
failed run counts toward the success rate only.
"""

from __future__ import annotations

import statistics
from collections.abc import Iterable
from dataclasses import dataclass

__all__ = ["DurationStats", "summarise"]


@dataclass(frozen=True)
class DurationStats:
    count: int
    """Runs that succeeded (each gives one duration)."""
    failures: int
    median: float
    q1: float
    q3: float
    stdev: float
    """Sample standard deviation; 0 with fewer than two runs."""
    mean: float
    minimum: float
    maximum: float

    @property
    def iqr(self) -> float:
        return self.q3 - self.q1

    @property
    def attempts(self) -> int:
        return self.count + self.failures

    @property
    def success_rate(self) -> float:
        return self.count / self.attempts if self.attempts else 0.0

    def expected_cost(self) -> float:
        """Expected time spent per success: a run that fails half the time costs
        twice its duration (it is redone)."""
        if not self.count:
            return float("inf")
        return self.median / self.success_rate

    def to_dict(self) -> dict[str, float | int]:
        return {
            "count": self.count,
            "failures": self.failures,
            "success_rate": round(self.success_rate, 4),
            "median": round(self.median, 4),
            "iqr": round(self.iqr, 4),
            "stdev": round(self.stdev, 4),
            "mean": round(self.mean, 4),
            "min": round(self.minimum, 4),
            "max": round(self.maximum, 4),
        }


def summarise(durations: Iterable[float], failures: int = 0) -> DurationStats:
    """The statistics of the durations of the successful runs, plus ``failures``."""
    values = sorted(durations)
    if not values:
        nan = float("nan")
        return DurationStats(0, failures, nan, nan, nan, nan, nan, nan, nan)
    if len(values) == 1:
        q1 = q3 = values[0]
    else:
        q1, _, q3 = statistics.quantiles(values, n=4, method="inclusive")
    return DurationStats(
        count=len(values),
        failures=failures,
        median=statistics.median(values),
        q1=q1,
        q3=q3,
        stdev=statistics.stdev(values) if len(values) > 1 else 0.0,
        mean=statistics.fmean(values),
        minimum=values[0],
        maximum=values[-1],
    )
