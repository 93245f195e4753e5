"""The performer base class: implement ``execute()``, the framework does the rest.

A performer is what turns an action of the plan into work on a robot. The framework
here owns the whole PlanSys2 protocol on the performer's side, so an adapter writer
implements one coroutine and never touches the auction:

* it answers a REQUEST only when idle, not committed to another auction, serving that
  action name, and when ``specialized_arguments`` match position by position (an
  empty string matches anything), exactly PlanSys2's rule;
* after a RESPONSE it is *committed*: it bids nowhere else until CONFIRM or REJECT
  arrives, or until ``commit_timeout`` passes, so a lost CONFIRM never wedges it;
* CONFIRM starts ``execute(goal)`` as a task; returning sends FINISH(success),
  raising :class:`ActionFailed` sends FINISH(failure) with its message, any other
  exception sends FINISH(failure) naming the exception and the performer stays up;
* CANCEL cancels the task (``asyncio.CancelledError`` inside ``execute``), then
  ``on_cancel(goal)`` runs (stop the motors); no FINISH follows a cancel;
* a heartbeat (:class:`ActionPerformerStatus`) goes out every ``heartbeat_period``
  and on every state change, which is what the executor's liveness check watches.

Performers never change the knowledge: the executor applies the action's effects.
Adapters may publish telemetry (e.g. a battery level) into the knowledge.
"""

from __future__ import annotations

import asyncio
import logging
from abc import abstractmethod
from collections.abc import Mapping, Sequence
from functools import partial
from typing import TYPE_CHECKING, Any

from plansys_bridge.clock import VirtualTimeEventLoop, stamp_loop
from plansys_bridge.errors import HubError
from plansys_bridge.hub.messages import (
    ActionPerformerStatus,
    ExecutionType,
    PerformerState,
    Topics,
    performer_statuses,
)
from plansys_bridge.hub.transport import Subscription
from plansys_bridge.performers.entry import PerformerConfig, construct
from plansys_bridge.performers.goal import (
    ActionFailed,
    ActionGoal,
    PerformerContext,
    arguments_match,
)
from plansys_bridge.performers.listening import listen
from plansys_bridge.performers.protocol import PerformerProtocol

if TYPE_CHECKING:
    from plansys_bridge.performers.bid_costs import BidCosts

__all__ = [
    "ActionFailed",
    "ActionGoal",
    "ActionPerformer",
    "PerformerConfig",
    "PerformerContext",
    "arguments_match",
]

log = logging.getLogger(__name__)

_STATUS = Topics.PERFORMERS_STATUS
_get_running_loop = asyncio._get_running_loop
_new = object.__new__


class ActionPerformer(PerformerProtocol):
    """Base class of every performer; subclasses implement :meth:`execute` (and declare
    their mission-file settings as :class:`~plansys_bridge.performers.kind.PerformerKind`
    says)."""

    def __init__(
        self,
        context: PerformerContext,
        node_name: str,
        actions: Mapping[str, Sequence[str]],
        *,
        heartbeat_period: float = 1.0,
        commit_timeout: float = 2.0,
    ) -> None:
        if not node_name:
            raise ValueError("a performer needs a non-empty node_name")
        if not actions:
            raise ValueError(f"performer {node_name!r} serves no action")
        if not heartbeat_period > 0:
            raise ValueError(f"heartbeat_period must be > 0, got {heartbeat_period!r}")
        if not commit_timeout > 0:
            raise ValueError(f"commit_timeout must be > 0, got {commit_timeout!r}")
        self.context = context
        self.hub = context.hub
        self.clock = context.clock
        self.node_name = node_name
        self.actions: dict[str, tuple[str, ...]] = {
            name: tuple(args) for name, args in actions.items()
        }
        self.heartbeat_period = float(heartbeat_period)
        self.commit_timeout = float(commit_timeout)
        self.state = PerformerState.NOT_READY
        self.goal: ActionGoal | None = None
        """The goal being executed (None when idle)."""
        self.completion = 0.0
        self.executed = 0
        """Goals started so far."""
        self._committed: ActionGoal | None = None
        self._committed_bid: float | None = None
        self._commit_deadline = 0.0
        """Loop time the commitment lapses at (checked when it matters, no timer: a
        timer per RESPONSE was a good part of an auction's cost with many bidders)."""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stamp_loop: VirtualTimeEventLoop | None = None
        self._status_fields: list[dict[str, object]] | None = None
        """Per action served, the fields of its status that do not change (set at
        start, in :class:`ActionPerformerStatus`'s order after stamp and state)."""
        """The loop whose time is the clock's while it runs (see :func:`stamp_loop`)."""
        self._task: asyncio.Task[None] | None = None
        self._cancelling = False
        self._subs: list[Subscription] = []
        self._heartbeat_timer: asyncio.TimerHandle | None = None
        self._running = False
        self._own_serves = type(self).serves is not ActionPerformer.serves
        self._own_accepts = type(self).accepts is not ActionPerformer.accepts
        """Only a subclass's own filter is asked (the base one accepts everything)."""
        """A subclass decides what it serves itself: ask it (else the same rule is
        read off the REQUEST before any goal is built)."""
        self._own_bid = type(self).bid is not ActionPerformer.bid
        """The base class's bid (None) is not asked for: a call less per RESPONSE."""
        self._plain_finish = (
            type(self)._finish is ActionPerformer._finish
            and type(self)._send is ActionPerformer._send
        )
        """FINISH(success) is sent without :meth:`_finish` and :meth:`_send` unless a
        subclass hooks one of them (fault injection drops FINISHes there)."""
        hooked = type(self)._publish is not ActionPerformer._publish
        self._out = self._publish if hooked else self.hub.publish
        """Where messages go: the hub's publish itself unless a subclass hooks
        :meth:`_publish` (fault injection), a call less per message otherwise."""
        self._out_many = self._publish_each if hooked else self.hub.publish_many
        """Where the statuses of one change of state go, in one call unless hooked."""
        self.bid_costs: BidCosts | None = context.bid_costs.get(node_name)
        """Learned costs (the mission's ``bid_costs:``); where they know the action
        they are bid instead of :meth:`bid`."""

    # ------------------------------------------------------------------ hooks

    async def setup(self) -> None:
        """Optional: connect to the hardware before the performer takes part in auctions."""
        return None

    def connects_to(self) -> str | None:
        """Optional: what ``setup()`` connects to (a URL, a bus), shown while it waits."""
        return None

    async def teardown(self) -> None:
        """Optional: release the hardware after the performer stopped."""
        return None

    def bid(self, goal: ActionGoal) -> float | None:
        """Optional cost for best-bid auctions; ``math.inf`` means "do not answer"."""
        return None

    def accepts(self, goal: ActionGoal) -> bool:
        """Optional extra filter run after the action and argument checks."""
        return True

    @abstractmethod
    async def execute(self, goal: ActionGoal) -> str | None:
        """Do the action. Return = success (the text is FINISH's status).

        Raise :class:`ActionFailed` to fail. A cancel arrives as
        ``asyncio.CancelledError``; let it propagate after any quick clean-up.
        """

    async def on_cancel(self, goal: ActionGoal) -> None:
        """Optional: stop the hardware after ``goal`` was cancelled."""
        return None

    # ------------------------------------------------------------------ lifecycle

    @property
    def running(self) -> bool:
        return self._running

    @property
    def busy(self) -> bool:
        return self._task is not None

    async def start(self) -> None:
        """Run ``setup()``, subscribe to the hub and start the heartbeat."""
        if self._running:
            return
        try:
            await self.setup()
        except Exception:
            self.state = PerformerState.FAILURE
            self._publish_status()
            raise
        self._loop = asyncio.get_running_loop()
        self._stamp_loop = stamp_loop(self.clock, self._loop)
        self._status_fields = [
            {"action": action, "specialized_arguments": spec, "node_name": self.node_name}
            for action, spec in self.actions.items()
        ]
        # A subclass that hooks _on_action_msg hears every message there first.
        plain = type(self)._on_action_msg is ActionPerformer._on_action_msg
        self._subs = listen(
            self.hub,
            self.node_name,
            self.actions,
            by_arguments=not self._own_serves,
            on_message=self._on_action_msg,
            # The router hands over only REQUESTs this performer serves (by_arguments).
            on_request=partial(self._on_request, routed=True) if plain else None,
        )
        self._running = True
        self.state = PerformerState.READY
        self._heartbeat()

    async def stop(self) -> None:
        """Cancel the running goal (its ``on_cancel`` runs), stop the heartbeat, ``teardown()``."""
        if not self._running:
            return
        self._running = False
        for sub in self._subs:
            sub.close()
        self._subs = []
        self._release_commitment()
        task = self._task
        if task is not None:
            self._cancelling = True
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)
        if self._heartbeat_timer is not None:
            self._heartbeat_timer.cancel()
            self._heartbeat_timer = None
        self.state = PerformerState.NOT_READY
        self._publish_status()
        # Let the loop deliver the NOT_READY status (and whatever was queued before it)
        # before returning, so "stopped" also means "said so".
        await asyncio.sleep(0)
        await self.teardown()

    async def __aenter__(self) -> ActionPerformer:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    # ------------------------------------------------------------------ helpers

    def feedback(self, completion: float, status: str = "") -> None:
        """Send FEEDBACK for the goal being executed (``completion`` in 0..1)."""
        goal = self.goal
        if goal is None:
            raise HubError(f"performer {self.node_name}: feedback() with no goal running")
        if self._cancelling:
            return  # the goal was cancelled: the executor no longer listens for it
        self.completion = min(1.0, max(0.0, float(completion)))
        self._send(ExecutionType.FEEDBACK, goal, completion=self.completion, status=status)

    def serves(self, goal: ActionGoal) -> bool:
        """Would this performer answer a REQUEST for ``goal`` when idle?"""
        spec = self.actions.get(goal.action)
        return spec is not None and arguments_match(spec, goal.arguments)

    # ------------------------------------------------------------------ outlets

    def _publish(self, topic: str, msg: object) -> None:
        """Every message the performer sends goes through here (fault injection hooks it)."""
        self.hub.publish(topic, msg)

    def _publish_each(self, topic: str, messages: Sequence[object]) -> None:
        for msg in messages:
            self._publish(topic, msg)

    def _publish_status(self) -> None:
        # One status per action served, published together (same messages, same
        # order): a change of state costs one publish, not one per action. The stamp
        # is read off the virtual loop when that is what now() would return.
        loop = self._stamp_loop
        stamp = (
            loop._virtual_now
            if loop is not None and _get_running_loop() is loop
            else self.clock.now()
        )
        served = self._status_fields
        if served is None:  # not started
            self._out_many(
                _STATUS, performer_statuses(stamp, self.state, self.actions.items(), self.node_name)
            )
            return
        # performer_statuses, inlined from the fields kept at start: two changes of
        # state per executed action
        state = self.state
        made = []
        for fields in served:
            msg = _new(ActionPerformerStatus)
            kept = msg.__dict__
            kept["status_stamp"] = stamp
            kept["state"] = state
            kept.update(fields)
            made.append(msg)
        self._out_many(_STATUS, made)

    def _heartbeat(self) -> None:
        # A timer callback rather than a task: heartbeats are most of the traffic of
        # a long virtual-clock run, and a callback costs a fraction of a task step.
        if not self._running:
            return
        self._publish_status()
        self._heartbeat_timer = asyncio.get_running_loop().call_later(
            self.heartbeat_period, self._heartbeat
        )

    # ------------------------------------------------------------------ configuration

    @classmethod
    def from_config(
        cls, config: Mapping[str, Any], context: PerformerContext, *, key: str = "performer"
    ) -> list[ActionPerformer]:
        """Build the performer(s) a mission entry describes (plugin factory).

        With a ``Settings`` model the validated settings reach ``__init__`` as
        ``settings=``; an older kind gets its ``settings_keys`` as keywords. A kind
        that builds several performers from one entry overrides this.
        """
        entry = cls.prepare(cls.parse_config(config, key=key), context)
        return [construct(cls, entry, context)]

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.node_name} {self.state.name}>"
