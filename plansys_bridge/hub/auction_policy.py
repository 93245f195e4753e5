"""What the executor asks of an auction and what it gets back.

:class:`AuctionPolicy` is the mission file's ``auction:`` section (how often to
re-send a REQUEST, when to give up, first responder or best bid, when a silent
performer counts as lost); :class:`ActionOutcome` is how one auctioned action ended;
:class:`ClientPhase` where the client is, and :data:`FeedbackCallback` what it calls
with progress. The protocol itself is :class:`~plansys_bridge.hub.auction.ActionClient`.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.settings import is_number, settings_from_mapping

__all__ = [
    "ActionOutcome",
    "AuctionPolicy",
    "ClientPhase",
    "FeedbackCallback",
    "action_outcome",
    "full_action_name",
]

FeedbackCallback = Callable[[float, str], None]
"""Called as ``feedback_cb(completion, status)`` for every FEEDBACK of the confirmed performer."""


class ClientPhase(enum.Enum):
    NEW = "new"
    AUCTION = "auction"
    EXECUTING = "executing"
    DONE = "done"


def full_action_name(action: str, arguments: Sequence[str]) -> str:
    """PlanSys2's action text: ``(move r2d2 kitchen bedroom)``."""
    return "(" + " ".join((action, *arguments)) + ")"


@dataclass(frozen=True)
class AuctionPolicy:
    """How the executor runs an auction; the mission file's ``auction:`` settings."""

    retry_period: float = 1.0
    """Re-send REQUEST this often (loop seconds) while nobody answers."""
    give_up_after: float = 30.0
    """Stop the auction (and the REQUESTs) if nobody answered after this long."""
    selection: Literal["first", "best_bid"] = "first"
    """``first``: PlanSys2's first responder wins; ``best_bid``: lowest bid wins."""
    bid_window: float = 0.05
    """With ``best_bid``: how long to collect bids after the first RESPONSE.

    Keep it well under the performers' ``commit_timeout`` (2 s by default): a bidder
    stops waiting for CONFIRM after that and would then be declared lost."""
    liveness_timeout: float = 5.0
    """A confirmed performer silent (no FEEDBACK, no RUNNING heartbeat) this long is lost."""
    reauctions: int = 1
    """How many times an action whose performer was lost is auctioned again."""

    def __post_init__(self) -> None:
        for name in ("retry_period", "give_up_after", "liveness_timeout"):
            value = getattr(self, name)
            if not is_number(value) or not value > 0:
                raise ConfigError(f"must be a number > 0, got {value!r}", key=f"auction.{name}")
        if not is_number(self.bid_window) or self.bid_window < 0:
            raise ConfigError(
                f"must be a number >= 0, got {self.bid_window!r}", key="auction.bid_window"
            )
        if isinstance(self.reauctions, bool) or not isinstance(self.reauctions, int):
            raise ConfigError(
                f"must be an integer, got {self.reauctions!r}", key="auction.reauctions"
            )
        if self.reauctions < 0:
            raise ConfigError(f"must be >= 0, got {self.reauctions}", key="auction.reauctions")
        if self.selection not in ("first", "best_bid"):
            raise ConfigError(
                f"must be 'first' or 'best_bid', got {self.selection!r}", key="auction.selection"
            )

    @classmethod
    def from_config(cls, config: Mapping[str, Any] | None, key: str = "auction") -> AuctionPolicy:
        """Build from a mapping, rejecting unknown keys with ``ConfigError(key=...)``."""
        return settings_from_mapping(cls, config, key)


@dataclass(frozen=True)
class ActionOutcome:
    """How one action ended, as the executor sees it."""

    success: bool
    status: str
    """The performer's FINISH status, or why the action failed or stopped."""
    completion: float
    performer: str
    """The node that last held the action ("" if none was ever confirmed)."""
    reauctioned: int
    cancelled: bool = False
    gave_up: bool = False
    """Nobody answered the REQUEST within ``give_up_after``."""
    lost_performers: tuple[str, ...] = field(default_factory=tuple)
    """Performers declared lost (no feedback or heartbeat) during this action."""


def action_outcome(
    success: bool,
    status: str,
    completion: float,
    performer: str,
    reauctioned: int,
    cancelled: bool,
    gave_up: bool,
    lost_performers: tuple[str, ...],
) -> ActionOutcome:
    """``ActionOutcome(...)`` for the client's end of every action: a frozen
    dataclass's ``__init__`` sets each of the eight fields through
    ``object.__setattr__``; an outcome made here is new and not yet shared, so its
    fields are filled in at once (as :func:`~plansys_bridge.hub.messages.action_execution`
    does for a message)."""
    outcome = _new(ActionOutcome)
    outcome.__dict__.update(
        success=success,
        status=status,
        completion=completion,
        performer=performer,
        reauctioned=reauctioned,
        cancelled=cancelled,
        gave_up=gave_up,
        lost_performers=lost_performers,
    )
    return outcome


_new = object.__new__
