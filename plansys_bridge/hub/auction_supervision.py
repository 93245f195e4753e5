"""The executor's side of the auction once a performer is confirmed: follow it.

A confirmed performer reports FEEDBACK while it works and FINISH when done; late
RESPONSEs of other bidders get a REJECT. A performer silent (neither FEEDBACK nor a
RUNNING heartbeat) for ``liveness_timeout`` is declared lost: it gets a CANCEL in case
it is only mute, and the action is auctioned again among the others (PlanSys2
#399/#400 leave it RUNNING forever). Kept apart from the bidding in
:mod:`plansys_bridge.hub.auction` so each part reads on its own.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

from plansys_bridge.hub.auction_policy import AuctionPolicy, FeedbackCallback
from plansys_bridge.hub.liveness import LivenessTable
from plansys_bridge.hub.messages import ActionExecution, ExecutionType

__all__ = ["Supervision"]

_RESPONSE = ExecutionType.RESPONSE
_FEEDBACK = ExecutionType.FEEDBACK
_REJECT = ExecutionType.REJECT


class Supervision:
    """The part of :class:`~plansys_bridge.hub.auction.ActionClient` that follows the
    confirmed performer (a mixin: the client holds the state and the plumbing)."""

    performer: str
    completion: float
    status: str
    policy: AuctionPolicy
    _loop: asyncio.AbstractEventLoop
    _last_seen: float
    _feedback_cb: FeedbackCallback | None
    _liveness: LivenessTable | None
    _excluded: frozenset[str]
    _lost: tuple[str, ...]
    _reauctioned: int

    if TYPE_CHECKING:  # the client's plumbing

        def _send(self, kind: ExecutionType, node_id: str) -> None: ...
        def _send_cancel(self) -> None: ...
        def _arm(self, deadline: float) -> None: ...
        def _fail(self, exc: Exception) -> None: ...
        def _begin_auction(self) -> None: ...
        def _finish(
            self, success: bool, status: str, *, cancelled: bool = False, gave_up: bool = False
        ) -> None: ...

    def _on_supervised(self, msg: ActionExecution) -> None:
        """A message while the confirmed performer works."""
        node = msg.node_id
        winner = self.performer
        kind = msg.type
        if kind is _RESPONSE:
            if node != winner:
                self._send(_REJECT, node)  # late responder
            return
        if node != winner:
            return  # a lost performer's late words; it was cancelled
        self._last_seen = self._loop.time()
        if kind is _FEEDBACK:
            self.completion = float(msg.completion)
            self.status = msg.status
            if self._feedback_cb is not None:
                try:
                    self._feedback_cb(self.completion, self.status)
                except Exception as exc:
                    self._fail(exc)
            return
        # FINISH
        self.completion = 1.0 if msg.success else max(self.completion, float(msg.completion))
        self._finish(msg.success, msg.status or ("succeeded" if msg.success else "failed"))

    def _check_alive(self) -> None:
        """The timer in execution: is the confirmed performer still heard from?"""
        loop = self._loop
        timeout = self.policy.liveness_timeout
        while True:
            deadline = self._last_seen + timeout
            if loop.time() < deadline:
                self._arm(deadline)
                return
            liveness = self._liveness
            heard = liveness.last_running(self.performer) if liveness is not None else None
            if heard is None or heard <= self._last_seen:
                self._performer_lost()
                return
            self._last_seen = heard  # its RUNNING heartbeats kept it alive

    def _performer_lost(self) -> None:
        # Stop it in case it is only mute, and never pick it again.
        winner = self.performer
        self._send_cancel()
        self._excluded = self._excluded | {winner}
        self._lost = (*self._lost, winner)
        reauctioned = self._reauctioned
        if reauctioned >= self.policy.reauctions:
            why = (
                f"performer {winner} lost: neither feedback nor heartbeat for "
                f"{self.policy.liveness_timeout:g} s"
            )
            why += (
                f"; re-auctioned {reauctioned} time(s), giving up"
                if reauctioned
                else "; re-auction disabled"
            )
            self._finish(False, why)
            return
        self._reauctioned += 1
        self._begin_auction()
