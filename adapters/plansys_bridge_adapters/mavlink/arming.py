"""What ArduPilot's arming refusals say, and which of them waiting will cure.

A refused arm comes with ``PreArm: ...`` / ``Arm: ...`` STATUSTEXTs naming the
failing check. Reasons a vehicle gives while it is still starting up (no position
estimate, sensors settling) go away by themselves; any other (a battery below its
arming voltage, a failing check) does not, and the client stops retrying.
"""

from __future__ import annotations

from collections.abc import Iterable

from .vehicle_state import StatusText

ARMING_TEXT_PREFIXES = ("prearm:", "arm:")

STARTING_UP_WORDS = (
    "position estimate",
    "waiting",
    "initialising",
    "initializing",
    "settling",
    "calibrating",
    "ekf",
    "ahrs",
)
"""Arming refusals that a vehicle still starting up gives (retried, not final)."""


def is_arming_text(text: str) -> bool:
    return text.lower().startswith(ARMING_TEXT_PREFIXES)


def starting_up(reason: str) -> bool:
    """``reason`` is one a vehicle still starting up gives (worth retrying)."""
    lowered = reason.lower()
    return any(word in lowered for word in STARTING_UP_WORDS)


def arming_texts(statustexts: Iterable[StatusText], since: float) -> str:
    """The last three distinct arming STATUSTEXTs heard at or after ``since``."""
    seen: list[str] = []
    for entry in statustexts:
        if is_arming_text(entry.text) and entry.stamp >= since and entry.text not in seen:
            seen.append(entry.text)
    return "; ".join(seen[-3:])
