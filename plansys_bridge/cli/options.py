"""Checks of the numeric command-line options the subcommands share.

argparse turns ``--timeout abc`` into an error but takes ``nan``, ``inf``, ``0`` and
``-1`` as floats; a time scale of ``inf`` then hangs a run and a ``nan`` timeout
reaches the solver as a time limit in the past. These checks run first in each
handler and raise a :class:`~plansys_bridge.errors.ConfigError` keyed by the option
(``error: --time-scale: must be a finite number > 0, got nan``, exit status 2).
"""

from __future__ import annotations

import math

from plansys_bridge.errors import ConfigError

__all__ = ["check_at_least", "check_non_negative", "check_positive"]


def check_positive(value: float | None, option: str) -> None:
    """``value`` (when given) is a finite number > 0."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise ConfigError(f"must be a finite number > 0, got {value}", key=option)


def check_non_negative(value: float | None, option: str) -> None:
    """``value`` (when given) is a finite number >= 0."""
    if value is not None and not (math.isfinite(value) and value >= 0):
        raise ConfigError(f"must be a finite number >= 0, got {value}", key=option)


def check_at_least(value: int | None, minimum: int, option: str) -> None:
    """``value`` (when given) is an integer >= ``minimum``."""
    if value is not None and value < minimum:
        raise ConfigError(f"must be >= {minimum}, got {value}", key=option)
