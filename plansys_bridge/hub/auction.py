"""The executor's side of the auction: find a performer for one action and follow it.

PlanSys2's protocol, on ``actions_hub``: REQUEST (re-sent every ``retry_period`` while
nobody answers), RESPONSE from each willing performer, CONFIRM to the winner and
REJECT to the others, FEEDBACK while it works, FINISH when done, CANCEL to abort
(no FINISH follows a cancel). Where PlanSys2 falls short this client does better:

* after ``give_up_after`` it stops re-sending REQUESTs (PlanSys2 #365 keeps sending);
* a confirmed performer that sends neither FEEDBACK nor a RUNNING heartbeat for
  ``liveness_timeout`` is declared lost: it gets a CANCEL and the action is
  re-auctioned among the other performers, ``reauctions`` times at most, then the
  action fails saying why (PlanSys2 #399/#400 leave it RUNNING forever);
* ``selection="best_bid"`` collects RESPONSEs for ``bid_window`` and confirms the
  cheapest bid (ties by arrival) instead of the first responder;
* ``request_id`` tells apart two plans running the same action text at once.

Only loop time is used (``loop.time()``, ``call_at``), so the client runs unchanged on
the wall clock and on the virtual clock.
"""

from __future__ import annotations

import asyncio
import enum
import itertools
import math
from collections import deque
from collections.abc import Callable, Sequence

from plansys_bridge.errors import HubError
from plansys_bridge.hub.auction_policy import ActionOutcome, AuctionPolicy, full_action_name
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.liveness import LivenessTable
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionPerformerStatus,
    ExecutionType,
    Topics,
    action_execution,
    readdressed,
)
from plansys_bridge.hub.routing import client_keys

__all__ = [
    "ActionClient",
    "ActionOutcome",
    "AuctionPolicy",
    "ClientPhase",
    "FeedbackCallback",
    "full_action_name",
]

FeedbackCallback = Callable[[float, str], None]
"""Called as ``feedback_cb(completion, status)`` for every FEEDBACK of the confirmed performer."""

_request_ids = itertools.count(1)


class ClientPhase(enum.Enum):
    NEW = "new"
    AUCTION = "auction"
    EXECUTING = "executing"
    DONE = "done"


_INCOMING = frozenset({ExecutionType.RESPONSE, ExecutionType.FEEDBACK, ExecutionType.FINISH})
_LISTENING = (ClientPhase.AUCTION, ClientPhase.EXECUTING)
"""A tuple, not a set: ``in`` tries identity first, where a set hashes a plain Enum
member in Python."""
_RESPONSE = ExecutionType.RESPONSE
"""Read once: an enum member read off its class costs about 0.3 us on Python 3.11,
and the bidding loop compares every RESPONSE of an auction with it."""


class ActionClient:
    """Runs the auction for one action instance and follows it to its end.

    ``await run()`` returns an :class:`ActionOutcome` (it never raises for a failed
    action); ``cancel()`` stops it from outside, and so does cancelling the task that
    awaits ``run()``. Either way the confirmed performer receives a CANCEL.
    """

    def __init__(
        self,
        hub: Hub,
        action: str,
        arguments: Sequence[str] = (),
        *,
        request_id: str | None = None,
        policy: AuctionPolicy | None = None,
    ) -> None:
        self.hub = hub
        self.action = action
        self.arguments = tuple(arguments)
        self.request_id = request_id if request_id is not None else f"{action}#{next(_request_ids)}"
        self.policy = policy if policy is not None else AuctionPolicy()
        self.phase = ClientPhase.NEW
        self.performer = ""
        """The confirmed performer's node name, once there is one."""
        self.completion = 0.0
        self.status = ""
        self.requests_sent = 0
        self._inbox: deque[ActionExecution] = deque()
        self._waiter: asyncio.Future[None] | None = None
        self._cancel_requested = False
        self._cancel_sent_to: str | None = None
        self._last_seen = 0.0
        self._loop: asyncio.AbstractEventLoop | None = None
        self._pending_bidders: list[str] = []
        self._confirm_cb: Callable[[str], None] | None = None
        self._freed = False
        """A matching performer went from RUNNING to READY: worth asking again now."""
        self._liveness: LivenessTable | None = None
        self._unwatch: Callable[[], None] = _nothing

    @property
    def full_name(self) -> str:
        return full_action_name(self.action, self.arguments)

    def __repr__(self) -> str:
        return f"<ActionClient {self.full_name} [{self.request_id}] {self.phase.value}>"

    # ------------------------------------------------------------------ public API

    async def run(
        self,
        feedback_cb: FeedbackCallback | None = None,
        *,
        confirm_cb: Callable[[str], None] | None = None,
    ) -> ActionOutcome:
        """Auction the action, follow its performer, and return how it ended.

        ``confirm_cb(node_name)`` is called each time a performer is confirmed (again
        after a re-auction): the moment the action really starts executing.
        """
        if self.phase is not ClientPhase.NEW:
            raise HubError(f"{self!r}: run() may be called only once")
        self._confirm_cb = confirm_cb
        self._loop = asyncio.get_running_loop()
        self._liveness = self.hub.liveness
        keys = client_keys(self.request_id, self.action, self.arguments)
        sub = self.hub.subscribe(Topics.ACTIONS_HUB, self._on_action_msg, keys=keys)
        try:
            return await self._run(feedback_cb)
        except BaseException:
            # Cancelled from outside (a halted behaviour tree) or a failing callback:
            # never leave a performer working, or one committed to us, behind.
            self._reject_pending()
            if self.phase is ClientPhase.EXECUTING:
                self._send_cancel()
            raise
        finally:
            self.phase = ClientPhase.DONE
            sub.close()

    def cancel(self) -> None:
        """Stop the action: CANCEL to the confirmed performer; ``run()`` returns cancelled."""
        if self.phase is ClientPhase.DONE or self._cancel_requested:
            return
        self._cancel_requested = True
        if self.phase is ClientPhase.EXECUTING:
            self._send_cancel()
        self._wake()

    # ------------------------------------------------------------------ protocol

    async def _run(self, feedback_cb: FeedbackCallback | None) -> ActionOutcome:
        excluded: set[str] = set()
        lost: list[str] = []
        reauctioned = 0
        while True:
            winner = await self._auction(excluded)
            if self._cancel_requested:
                return self._outcome(False, "cancelled", reauctioned, lost, cancelled=True)
            if winner is None:
                why = (
                    f"no performer answered the REQUEST for {self.full_name} "
                    f"within {self.policy.give_up_after:g} s"
                )
                if lost:
                    why += f" (after losing {', '.join(lost)})"
                return self._outcome(False, why, reauctioned, lost, gave_up=True)
            outcome = await self._supervise(winner, feedback_cb, reauctioned, lost)
            if outcome is not None:
                return outcome
            # Lost: stop it in case it is only mute, and never pick it again.
            self._send_cancel()
            excluded.add(winner)
            lost.append(winner)
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
                return self._outcome(False, why, reauctioned, lost)
            reauctioned += 1

    async def _auction(self, excluded: set[str]) -> str | None:
        """Run one auction; return the confirmed node, or None (gave up / cancelled)."""
        loop = self._require_loop()
        policy = self.policy
        self.phase = ClientPhase.AUCTION
        self.performer = ""
        self.completion = 0.0
        self._cancel_sent_to = None
        start = loop.time()
        give_up_at = start + policy.give_up_after
        self._pending_bidders = []
        self._freed = False
        if self._liveness is not None:
            self._unwatch = self._liveness.watch(self.action, self._on_freed)
        try:
            return await self._bidding(excluded, start, give_up_at)
        finally:
            self._unwatch()
            self._unwatch = _nothing

    async def _bidding(self, excluded: set[str], start: float, give_up_at: float) -> str | None:
        loop = self._require_loop()
        policy = self.policy
        sent = 0
        bids: list[tuple[float, int, str]] = []
        seen: set[str] = set()
        bid_deadline = math.inf
        while True:
            if self._cancel_requested:
                self._reject_pending()
                return None
            now = loop.time()
            if bids and (policy.selection == "first" or now >= bid_deadline):
                break
            deadline: float
            if bids:
                deadline = bid_deadline
            else:
                if now >= give_up_at:
                    return None
                next_request = start + sent * policy.retry_period
                if self._freed and sent and start + sent * policy.retry_period < give_up_at:
                    # A performer that can serve us just finished its other action: ask
                    # at once, using up the next periodic REQUEST's slot, so the count
                    # stays one per retry period and none goes out after giving up.
                    self._freed = False
                    self._send(ExecutionType.REQUEST, "")
                    sent += 1
                elif now >= next_request:
                    self._send(ExecutionType.REQUEST, "")
                    sent += 1
                    # Catch up without a burst if the loop was held up for a while.
                    while start + sent * policy.retry_period <= now:
                        sent += 1
                deadline = min(start + sent * policy.retry_period, give_up_at)
            # RESPONSEs arrive in bursts: take those already in hand without a wait.
            inbox = self._inbox
            msg = inbox.popleft() if inbox else await self._next(deadline)
            if msg is None or msg.type is not _RESPONSE:
                continue  # FEEDBACK/FINISH of a performer dropped earlier: stale
            node = msg.node_id
            if node in excluded:
                self._send(ExecutionType.REJECT, node)
                continue
            if node in seen:
                continue  # a RESPONSE repeated for a re-sent REQUEST
            seen.add(node)
            self._pending_bidders.append(node)
            cost = msg.bid if msg.bid is not None and not math.isnan(msg.bid) else math.inf
            bids.append((cost, len(bids), node))
            if len(bids) == 1:
                bid_deadline = loop.time() + policy.bid_window
        winner = min(bids)[2]
        self._pending_bidders.remove(winner)
        self._send(ExecutionType.CONFIRM, winner)
        self.performer = winner
        self.phase = ClientPhase.EXECUTING
        self._reject_pending()
        if self._confirm_cb is not None:
            self._confirm_cb(winner)
        return winner

    async def _supervise(
        self,
        winner: str,
        feedback_cb: FeedbackCallback | None,
        reauctioned: int,
        lost: list[str],
    ) -> ActionOutcome | None:
        """Follow the confirmed performer; None means it was declared lost."""
        loop = self._require_loop()
        self._last_seen = loop.time()
        self.completion = 0.0
        while True:
            if self._cancel_requested:
                self._send_cancel()
                return self._outcome(False, "cancelled", reauctioned, lost, cancelled=True)
            deadline = self._last_seen + self.policy.liveness_timeout
            if loop.time() >= deadline:
                heard = self._liveness.last_running(winner) if self._liveness else None
                if heard is None or heard <= self._last_seen:
                    return None
                self._last_seen = heard  # its RUNNING heartbeats kept it alive
                continue
            msg = await self._next(deadline)
            if msg is None:
                continue
            if msg.type is ExecutionType.RESPONSE:
                if msg.node_id != winner:
                    self._send(ExecutionType.REJECT, msg.node_id)  # late responder
                continue
            if msg.node_id != winner:
                continue  # a lost performer's late words; it was cancelled
            self._last_seen = loop.time()
            if msg.type is ExecutionType.FEEDBACK:
                self.completion = float(msg.completion)
                self.status = msg.status
                if feedback_cb is not None:
                    feedback_cb(self.completion, self.status)
                continue
            # FINISH
            self.completion = 1.0 if msg.success else max(self.completion, float(msg.completion))
            status = msg.status or ("succeeded" if msg.success else "failed")
            self.status = status
            return self._outcome(msg.success, status, reauctioned, lost)

    # ------------------------------------------------------------------ plumbing

    def _outcome(
        self,
        success: bool,
        status: str,
        reauctioned: int,
        lost: list[str],
        *,
        cancelled: bool = False,
        gave_up: bool = False,
    ) -> ActionOutcome:
        self.status = status
        return ActionOutcome(
            success=success,
            status=status,
            completion=self.completion,
            performer=self.performer,
            reauctioned=reauctioned,
            cancelled=cancelled,
            gave_up=gave_up,
            lost_performers=tuple(lost),
        )

    def _require_loop(self) -> asyncio.AbstractEventLoop:
        if self._loop is None:  # pragma: no cover - run() sets it first
            raise HubError(f"{self!r} is not running")
        return self._loop

    def _send(self, kind: ExecutionType, node_id: str) -> None:
        if kind is ExecutionType.REQUEST:
            self.requests_sent += 1
        self.hub.publish(
            Topics.ACTIONS_HUB,
            action_execution(
                kind, node_id, self.action, self.arguments, request_id=self.request_id
            ),
        )

    def _send_cancel(self) -> None:
        if self.performer and self._cancel_sent_to != self.performer:
            self._cancel_sent_to = self.performer
            self._send(ExecutionType.CANCEL, self.performer)

    def _reject_pending(self) -> None:
        pending, self._pending_bidders = self._pending_bidders, []
        if not pending:
            return
        reject = action_execution(
            ExecutionType.REJECT, "", self.action, self.arguments, request_id=self.request_id
        )
        publish = self.hub.publish
        for node in pending:
            publish(Topics.ACTIONS_HUB, readdressed(reject, node))

    def _matches(self, msg: ActionExecution) -> bool:
        if msg.request_id and self.request_id and msg.request_id != self.request_id:
            return False
        return msg.action == self.action and tuple(msg.arguments) == self.arguments

    def _on_action_msg(self, msg: object) -> None:
        if (
            isinstance(msg, ActionExecution)
            and msg.type in _INCOMING
            and self._matches(msg)
            and self.phase in _LISTENING
        ):
            self._inbox.append(msg)
            waiter = self._waiter
            if waiter is not None and not waiter.done():
                waiter.set_result(None)

    def _on_freed(self, msg: ActionPerformerStatus) -> None:
        """The liveness table saw a performer of our action finish its other work."""
        if self.phase is ClientPhase.AUCTION and self._could_serve(msg):
            self._freed = True
            self._wake()

    def _could_serve(self, msg: ActionPerformerStatus) -> bool:
        """Does this heartbeat come from a performer whose action and specialised
        arguments (empty string = any) fit this request?"""
        if msg.action != self.action or len(msg.specialized_arguments) > len(self.arguments):
            return False
        return all(
            want in ("", have)
            for want, have in zip(msg.specialized_arguments, self.arguments, strict=False)
        )

    def _wake(self) -> None:
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)

    async def _next(self, deadline: float) -> ActionExecution | None:
        """The next matching message, or None at ``deadline`` (loop time) or on cancel()."""
        if self._inbox:
            return self._inbox.popleft()
        loop = self._require_loop()
        if loop.time() >= deadline or self._cancel_requested:
            return None
        waiter: asyncio.Future[None] = loop.create_future()
        self._waiter = waiter
        timer = loop.call_at(deadline, _resolve, waiter) if math.isfinite(deadline) else None
        try:
            await waiter
        finally:
            self._waiter = None
            if timer is not None:
                timer.cancel()
        return self._inbox.popleft() if self._inbox else None


def _nothing() -> None:
    return None


def _resolve(waiter: asyncio.Future[None]) -> None:
    if not waiter.done():
        waiter.set_result(None)
