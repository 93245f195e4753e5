"""Learned bid costs: what each performer bids in a best-bid auction.

``plansys-bridge learn --costs FILE`` writes, per performer, the expected seconds
per success of each action it ran (by ground action text and by action name);
a mission names the file with ``bid_costs:``. A performer with an entry for the
action being auctioned bids that cost instead of its own estimate (which knows
nothing of how its past runs went); without one it bids as before.

The file::

    performers:
      robot1_base: {move: 4.1, "(move robot1 pantry_zone cooking_zone)": 4.6}
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plansys_bridge.errors import ConfigError
from plansys_bridge.textfile import TextFileError, read_text

__all__ = ["BidCosts", "load_bid_costs"]


@dataclass(frozen=True)
class BidCosts:
    """One performer's learned costs: ground action text or action name -> seconds."""

    costs: Mapping[str, float]

    def cost(self, action: str, arguments: Sequence[str]) -> float | None:
        text = "(" + " ".join((action, *arguments)).lower() + ")"
        found = self.costs.get(text)
        return found if found is not None else self.costs.get(action.lower())


def load_bid_costs(path: str | Path, key: str = "bid_costs") -> dict[str, BidCosts]:
    """performer name -> its costs, from a file ``learn --costs`` wrote; errors name
    the file and the key path of the bad entry."""
    import yaml

    p = Path(path)
    try:
        data: Any = yaml.safe_load(read_text(p, "bid costs file"))
    except TextFileError as exc:
        raise ConfigError(exc.reason, key=key, file=str(exc.location or p)) from exc
    except yaml.YAMLError as exc:
        raise ConfigError(f"not valid YAML: {exc}", key=key, file=str(p)) from exc
    table = data.get("performers") if isinstance(data, dict) else None
    if not isinstance(table, dict):
        raise ConfigError("must map performers: to {performer: {action: seconds}}", file=str(p))
    out: dict[str, BidCosts] = {}
    for name, costs in table.items():
        if not isinstance(costs, dict):
            raise ConfigError("must map actions to seconds", key=f"performers.{name}", file=str(p))
        checked: dict[str, float] = {}
        for action, seconds in costs.items():
            where = f"performers.{name}.{action}"
            if isinstance(seconds, bool) or not isinstance(seconds, int | float):
                raise ConfigError(f"must be a number, got {seconds!r}", key=where, file=str(p))
            if not math.isfinite(seconds) or seconds < 0:
                raise ConfigError(f"must be >= 0 and finite, got {seconds}", key=where, file=str(p))
            checked[" ".join(str(action).lower().split())] = float(seconds)
        out[str(name)] = BidCosts(checked)
    return out
