"""Whether a vehicle still gets closer to its target, judged on its own clock.

ArduPilot says nothing when it cannot make headway: a copter flying into a wind
stronger than it can lean against stays in GUIDED, holds its altitude and drifts
backwards without a STATUSTEXT. The adapter notices from the vehicle's own
positions: when GLOBAL_POSITION_INT has not come at least :data:`MIN_GAIN_M` closer
to the target for ``window`` seconds of the vehicle's time (``time_boot_ms``), the
go-to fails, saying how far it is, how close it came and how fast it moves.
Vehicle time makes the rule the same at any SITL speedup and on hardware.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MIN_GAIN_M = 0.5
"""Metres closer that count as progress (GPS noise moves a vehicle standing still)."""


@dataclass
class Headway:
    """Progress towards one target; feed it with :meth:`update` on every position."""

    window: float
    """Vehicle seconds without progress that end the go-to."""
    best: float = math.inf
    """The closest the vehicle came (metres)."""
    best_at: float | None = None
    """Vehicle time (s) when it came that close."""
    last_at: float | None = None

    def update(self, remaining: float, vehicle_time: float | None) -> bool:
        """Record ``remaining`` metres at ``vehicle_time``; True while progress holds."""
        if vehicle_time is None:
            return True
        if self.last_at is not None and vehicle_time < self.last_at:
            self.best, self.best_at = math.inf, None  # the vehicle rebooted
        self.last_at = vehicle_time
        if self.best_at is None or remaining <= self.best - MIN_GAIN_M:
            self.best, self.best_at = remaining, vehicle_time
            return True
        return vehicle_time - self.best_at <= self.window

    def stalled_for(self) -> float:
        if self.best_at is None or self.last_at is None:
            return 0.0
        return self.last_at - self.best_at

    def describe(self, name: str, remaining: float, velocity: tuple[float, float, float]) -> str:
        """Why the go-to to ``name`` ends, in the vehicle's own figures."""
        return (
            f"no headway to {name}: {remaining:.1f} m away, no closer than {self.best:.1f} m "
            f"for {self.stalled_for():.0f} s of vehicle time, moving at "
            f"{math.hypot(velocity[0], velocity[1]):.1f} m/s over ground; the vehicle reports "
            "no fault (wind or a limit it cannot overcome)"
        )
