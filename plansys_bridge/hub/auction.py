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

The client is driven by its messages and one alarm (on a loop timer every client of
the loop shares, :mod:`.alarms`): each message is handled as the hub delivers it (a
RESPONSE may confirm at once). A coroutine that woke for every message cost a task
step, a future and a timer per wait, several times what handling the message costs;
``start()`` hands out the outcome future without even one task.
"""

from __future__ import annotations

import asyncio
import itertools
import math
from collections.abc import Callable, Sequence

from plansys_bridge.errors import HubError
from plansys_bridge.hub.alarms import Alarms, alarms_of
from plansys_bridge.hub.auction_policy import (
    ActionOutcome,
    AuctionPolicy,
    ClientPhase,
    FeedbackCallback,
    action_outcome,
    full_action_name,
)
from plansys_bridge.hub.auction_supervision import Supervision
from plansys_bridge.hub.client_state import ClientState
from plansys_bridge.hub.driven_future import DrivenFuture
from plansys_bridge.hub.freed_watch import FreedWatch, watch_of
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.liveness import could_serve
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionPerformerStatus,
    ExecutionType,
    Topics,
    action_execution,
    readdressed,
)

__all__ = [
    "ActionClient",
    "ActionOutcome",
    "AuctionPolicy",
    "ClientPhase",
    "FeedbackCallback",
    "full_action_name",
]

_request_ids = itertools.count(1)
_INCOMING = frozenset({ExecutionType.RESPONSE, ExecutionType.FEEDBACK, ExecutionType.FINISH})
_RESPONSE = ExecutionType.RESPONSE
"""Read once: an enum member read off its class costs about 0.3 us on Python 3.11,
and the bidding compares every RESPONSE of an auction with it."""
_FEEDBACK = ExecutionType.FEEDBACK
_FINISH = ExecutionType.FINISH
_CONFIRM = ExecutionType.CONFIRM
_HUB = Topics.ACTIONS_HUB
_REQUEST = ExecutionType.REQUEST
_REJECT = ExecutionType.REJECT
_AUCTION = ClientPhase.AUCTION
_EXECUTING = ClientPhase.EXECUTING


def _ignore(msg: object) -> None:
    """An ended client's router callback (the router skips it anyway: it is closed)."""


class ActionClient(ClientState, Supervision, DrivenFuture[ActionOutcome]):
    """Runs the auction for one action instance and follows it to its end.

    ``await run()`` returns an :class:`ActionOutcome` (it never raises for a failed
    action); ``cancel()`` stops it from outside, and so does cancelling the task that
    awaits ``run()`` or the future ``start()`` returns. Either way the confirmed
    performer receives a CANCEL.

    Following the confirmed performer is :class:`~.auction_supervision.Supervision`'s;
    the client's state and its defaults are :class:`~.client_state.ClientState`'s.
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
        self._pending_bidders: list[str] = []
        self._publish = hub.publish

    @property
    def full_name(self) -> str:
        return full_action_name(self.action, self.arguments)

    def __repr__(self) -> str:
        return f"<ActionClient {self.full_name} [{self.request_id}] {self.phase.value}>"

    async def run(
        self,
        feedback_cb: FeedbackCallback | None = None,
        *,
        confirm_cb: Callable[[str], None] | None = None,
    ) -> ActionOutcome:
        """Auction the action, follow its performer, and return how it ended.

        ``confirm_cb(node_name)`` is called each time a performer is confirmed (again
        after a re-auction): the moment the action really starts executing."""
        if self._done is not None:
            raise HubError(f"{self!r}: run() may be called only once")
        return await self.start(feedback_cb, confirm_cb=confirm_cb)

    def start(
        self,
        feedback_cb: FeedbackCallback | None = None,
        *,
        confirm_cb: Callable[[str], None] | None = None,
        soon: bool = False,
        settled_cb: Callable[[], None] | None = None,
        call_soon: Callable[..., object] | None = None,
    ) -> asyncio.Future[ActionOutcome]:
        """What :meth:`run` does, without a task (see :mod:`.driven_future`): send the
        first REQUEST and return the future of the outcome. Cancelling it stops the
        action as cancelling run()'s task does: pending bidders get a REJECT, the
        confirmed performer a CANCEL.

        ``soon``: subscribe and send the first REQUEST in a loop callback scheduled
        now, where a task made to await :meth:`run` took its first step. The executor
        starts actions within a tick that may still halt them (``halt_on_failure``):
        a halted action then sends nothing, and the hub sees the messages in the
        order a task gave, for one loop callback instead of three. ``call_soon``
        schedules that callback instead of the loop's (the executor's runs those of
        one tick in one loop callback, in order).

        ``settled_cb()`` is called right after the future is settled (see
        :mod:`.driven_future`): what a done callback would do, without its loop callback."""
        # the outcome future, watched for a cancel from outside (inlined: once per action)
        if self._done is not None:
            raise HubError(f"{self!r}: start() may be called only once")
        loop = self._loop = asyncio.get_running_loop()
        done: asyncio.Future[ActionOutcome] = loop.create_future()
        self._done = done
        done.add_done_callback(self._on_done)
        self._confirm_cb, self._feedback_cb = confirm_cb, feedback_cb
        self._settled_cb = settled_cb
        if soon:
            (call_soon or loop.call_soon)(self._begin_soon, done)
        elif (exc := self._begin(done)) is not None:
            raise exc
        return done

    def _abandon(self) -> None:
        """Never leave a performer working, or one committed to us, behind."""
        self._reject_pending()
        if self.phase is _EXECUTING:
            self._send_cancel()
        self._end()

    def cancel(self) -> None:
        """Stop the action: CANCEL to the confirmed performer; ``run()`` returns cancelled."""
        if self.phase is ClientPhase.DONE or self._cancel_requested:
            return
        self._cancel_requested = True
        if self.phase is _EXECUTING:
            self._send_cancel()
            self._finish(False, "cancelled", cancelled=True)
        elif self.phase is _AUCTION:  # NEW: the first step finds the request
            self._auction_step()

    # ------------------------------------------------------------------ auction

    def _begin_auction(self) -> None:
        """Start an auction: the first (from ``start()``, as ``_launch``, after
        subscribing) or another after losing the performer."""
        loop = self._loop
        if self._table is None:  # the first: listen, and find what the hub shares
            hub = self.hub
            liveness = self._liveness = hub.liveness
            watch = FreedWatch.last
            if watch is None or watch.liveness() is not liveness:
                watch = watch_of(liveness)
            self._watch = watch
            # join the table (ClientTable.join, inlined: once per action)
            table = self._table = hub.clients
            self.order = next(table.order)
            self.callback = self._on_action_msg
            held = table.by_request.setdefault(self.request_id, self)
            if held is not self:
                table.shared(held, self)
        self.phase = _AUCTION
        self.performer = ""
        self.completion = 0.0
        self._cancel_sent_to = None
        self._start = loop.time()
        self._give_up_at = self._start + self.policy.give_up_after
        self._pending_bidders = []
        self._freed = False
        self._sent = 0
        self._bids = []
        self._seen = set()
        self._bid_deadline = math.inf
        # wait for a freed performer of the action (FreedWatch.first, inlined but once
        # per action and hub)
        waiting = self._watch.waiting.get(self.action)
        if waiting is None:
            self._waiting = self._watch.first(self.action, self)
        else:
            waiting[self] = None
            self._waiting = waiting
        self._auction_step()

    _launch = _begin_auction

    def _auction_over(self) -> None:
        """Stop waiting for a freed performer."""
        waiting = self._waiting
        if waiting is not None:
            self._waiting = None
            del waiting[self]
            if not waiting:
                self._watch.idle(self.action)

    def _auction_step(self) -> None:
        """Move the auction on: confirm, give up, or (re-)send the REQUEST, then wait
        for the next message or the timer."""
        loop = self._loop
        policy = self.policy
        while True:
            if self._cancel_requested:
                self._reject_pending()
                self._finish(False, "cancelled", cancelled=True)
                return
            now = loop.time()
            if self._bids:
                deadline = self._bid_deadline
                if policy.selection == "first" or now >= deadline:
                    self._confirm()
                    return
            else:
                if now >= self._give_up_at:
                    self._give_up()
                    return
                start, sent, period = self._start, self._sent, policy.retry_period
                if self._freed and sent and start + sent * period < self._give_up_at:
                    # A performer that can serve us just finished its other action: ask
                    # at once, using up the next periodic REQUEST's slot, so the count
                    # stays one per retry period and none goes out after giving up.
                    self._freed = False
                    sent += 1
                elif now >= start + sent * period:
                    sent += 1
                    # Catch up without a burst if the loop was held up for a while.
                    while start + sent * period <= now:
                        sent += 1
                if sent != self._sent:  # a REQUEST (_send, inlined)
                    self._sent = sent
                    self.requests_sent += 1
                    self._publish(
                        _HUB,
                        action_execution(
                            _REQUEST, "", self.action, self.arguments, request_id=self.request_id
                        ),
                    )
                deadline = min(start + sent * period, self._give_up_at)
            if deadline > now:
                self._arm(deadline)
                return

    def _confirm(self) -> None:
        # _send and the early returns of _reject_pending and _arm inlined: once per action
        winner = min(self._bids)[2]
        self._pending_bidders.remove(winner)
        self._publish(
            _HUB,
            action_execution(
                _CONFIRM, winner, self.action, self.arguments, request_id=self.request_id
            ),
        )
        self.performer = winner
        self.phase = _EXECUTING
        if self._pending_bidders:
            self._reject_pending()
        self._auction_over()
        if self._confirm_cb is not None:
            try:
                self._confirm_cb(winner)
            except Exception as exc:
                self._fail(exc)
                return
        if self.phase is not _EXECUTING:
            return  # cancelled by the callback
        self._last_seen = now = self._loop.time()
        self.completion = 0.0
        deadline = now + self.policy.liveness_timeout
        if not self._alarm or self._alarm_at > deadline:
            self._arm(deadline)

    def _give_up(self) -> None:
        self._auction_over()
        why = (
            f"no performer answered the REQUEST for {self.full_name} "
            f"within {self.policy.give_up_after:g} s"
        )
        if self._lost:
            why += f" (after losing {', '.join(self._lost)})"
        self._finish(False, why, gave_up=True)

    # ------------------------------------------------------------------ plumbing

    def _finish(
        self, success: bool, status: str, *, cancelled: bool = False, gave_up: bool = False
    ) -> None:
        """The action is over: stop listening and hand ``run()`` its outcome."""
        self.status = status
        outcome = action_outcome(
            success,
            status,
            self.completion,
            self.performer,
            self._reauctioned,
            cancelled,
            gave_up,
            self._lost,
        )
        self._end()
        # _resolve, inlined: once per action
        done = self._done
        if done is not None and not done.done():
            done.remove_done_callback(self._on_done)
            done.set_result(outcome)
            settled = self._settled_cb  # _notify, inlined
            if settled is not None:
                self._settled_cb = None
                settled()

    def _fail(self, exc: Exception) -> None:
        """A callback raised: ``run()`` raises it, as when it was called there."""
        self._abandon()
        self._reject(exc)

    def _end(self) -> None:
        self.phase = ClientPhase.DONE
        if self._waiting is not None:
            self._auction_over()
        self._alarm = 0  # its alarm forgotten (Alarms.clear, inlined)
        self._alarm_at = math.inf
        # No cycle left through the caller's callbacks (which hold what holds the
        # client) or, below, its own bound method in the table: an ended client is
        # freed as soon as nobody holds it, not by the cyclic collector.
        self._confirm_cb = self._feedback_cb = None
        table = self._table
        if table is not None and not self.closed:  # leave (ClientTable.leave, inlined)
            self.closed = True
            self.callback = _ignore
            held = table.by_request.pop(self.request_id, None)
            if held is not self and held is not None:
                table.unshare(held, self)

    def _arm(self, deadline: float) -> None:
        """Be woken at ``deadline`` (loop time). One alarm serves every wait: one that
        rings earlier is kept, and the wait is taken up again when it rings. The
        alarm is the loop's (:mod:`.alarms`): one loop timer for every client."""
        if self._alarm and self._alarm_at <= deadline:
            return
        self._alarm_at = deadline
        alarms = Alarms.last
        loop = self._loop
        if alarms is None or alarms.loop() is not loop:
            alarms = alarms_of(loop)
        alarms.set(deadline, self)

    def _on_timer(self) -> None:
        self._alarm_at = math.inf
        if self.phase is _AUCTION:
            self._auction_step()
        elif self.phase is _EXECUTING:
            self._check_alive()

    def _send(self, kind: ExecutionType, node_id: str) -> None:
        if kind is _REQUEST:
            self.requests_sent += 1
        self._publish(
            _HUB,
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
            _REJECT, "", self.action, self.arguments, request_id=self.request_id
        )
        self.hub.publish_many(_HUB, [readdressed(reject, node) for node in pending])

    def _on_action_msg(self, msg: object) -> None:
        if (
            msg.__class__ is not ActionExecution and not isinstance(msg, ActionExecution)
        ) or msg.type not in _INCOMING:
            return
        # Is it about this request? (request_id when both have one, else the text)
        rid = msg.request_id
        if rid and self.request_id and rid != self.request_id:
            return
        arguments = msg.arguments
        if msg.action != self.action or (
            arguments != self.arguments and tuple(arguments) != self.arguments
        ):
            return
        phase = self.phase
        if phase is _EXECUTING:
            if msg.type is _FINISH and msg.node_id == self.performer:
                # _on_supervised's end, inlined: once per action
                success = msg.success
                self.completion = 1.0 if success else max(self.completion, float(msg.completion))
                self._finish(success, msg.status or ("succeeded" if success else "failed"))
            else:
                self._on_supervised(msg)
            return
        if phase is not _AUCTION:
            return
        # A bid (inlined: every bidder of an auction comes here)
        if msg.type is _RESPONSE:  # else: FEEDBACK/FINISH of a performer dropped earlier
            node = msg.node_id
            if node in self._excluded:
                self._send(_REJECT, node)
            elif node not in self._seen:  # else: a RESPONSE repeated for a re-sent REQUEST
                self._seen.add(node)
                self._pending_bidders.append(node)
                bid = msg.bid
                cost = bid if bid is not None and bid == bid else math.inf  # NaN: no cost
                bids = self._bids
                count = len(bids)
                bids.append((cost, count, node))
                if not count:
                    policy = self.policy
                    if policy.selection == "first":
                        self._confirm()  # what _auction_step does with a first bid
                        return
                    self._bid_deadline = self._loop.time() + policy.bid_window
                elif (
                    self._loop.time() < self._bid_deadline and self._alarm_at <= self._bid_deadline
                ):
                    return  # still collecting bids, the timer set: nothing else to do
        self._auction_step()

    def _on_freed(self, msg: ActionPerformerStatus) -> None:
        """The liveness table saw a performer of our action finish its other work."""
        if self.phase is _AUCTION and could_serve(msg, self.action, self.arguments):
            self._freed = True
            self._auction_step()
