"""The performer's side of the auction protocol, as PlanSys2 runs it.

REQUEST -> RESPONSE (when idle, uncommitted, serving the action), CONFIRM -> the goal
runs as a task -> FINISH, REJECT releases the commitment, CANCEL cancels the task.
:class:`~plansys_bridge.performers.base.ActionPerformer` inherits these handlers; they
live apart from its lifecycle and hooks so that each module stays readable, and
because they are the per-message hot path of every auction.
"""

from __future__ import annotations

import asyncio
import logging
import math
from abc import ABC
from collections.abc import Callable
from typing import TYPE_CHECKING

from plansys_bridge.hub.messages import (
    ActionExecution,
    ExecutionType,
    PerformerState,
    Topics,
    action_execution,
)
from plansys_bridge.performers.goal import (
    ActionFailed,
    ActionGoal,
    arguments_match,
    goal_of,
    last_request,
    same_goal,
)
from plansys_bridge.performers.kind import PerformerKind

if TYPE_CHECKING:
    from plansys_bridge.clock import Clock
    from plansys_bridge.hub.hub import Hub
    from plansys_bridge.performers.bid_costs import BidCosts

__all__ = ["PerformerProtocol"]

# The performer's log lines keep the logger they always had (base, where the class is).
log = logging.getLogger("plansys_bridge.performers.base")

# Read once: an enum member read off its class costs about 0.3 us on Python 3.11, and
# every performer compares every auction message it is handed with these.
_REQUEST = ExecutionType.REQUEST
_RESPONSE = ExecutionType.RESPONSE
_CONFIRM = ExecutionType.CONFIRM
_REJECT = ExecutionType.REJECT
_CANCEL = ExecutionType.CANCEL
_FINISH = ExecutionType.FINISH
_RUNNING = PerformerState.RUNNING
_READY = PerformerState.READY
_ACTIONS_HUB = Topics.ACTIONS_HUB
_INF = math.inf


class PerformerProtocol(PerformerKind, ABC):
    """The auction handlers of a performer (the state they use is set up by
    :class:`~plansys_bridge.performers.base.ActionPerformer`)."""

    hub: Hub
    clock: Clock
    node_name: str
    actions: dict[str, tuple[str, ...]]
    commit_timeout: float
    state: PerformerState
    goal: ActionGoal | None
    completion: float
    executed: int
    bid_costs: BidCosts | None
    _committed: ActionGoal | None
    _committed_bid: float | None
    _commit_deadline: float
    _loop: asyncio.AbstractEventLoop | None
    _task: asyncio.Task[None] | None
    _cancelling: bool
    _running: bool
    _own_serves: bool
    _own_accepts: bool
    _own_bid: bool
    _plain_finish: bool
    _out: Callable[[str, object], None]

    if TYPE_CHECKING:
        # The hooks and the outlets, defined by ActionPerformer.

        def serves(self, goal: ActionGoal) -> bool: ...

        def accepts(self, goal: ActionGoal) -> bool: ...

        def bid(self, goal: ActionGoal) -> float | None: ...

        async def execute(self, goal: ActionGoal) -> str | None: ...

        async def on_cancel(self, goal: ActionGoal) -> None: ...

        def _publish_status(self) -> None: ...

    @property
    def committed(self) -> ActionGoal | None:
        """The request this performer answered and awaits CONFIRM/REJECT for."""
        goal = self._committed
        loop = self._loop
        if goal is not None and loop is not None and loop.time() >= self._commit_deadline:
            self._lapse(goal)
            return None
        return goal

    def _lapse(self, goal: ActionGoal) -> None:
        """No CONFIRM/REJECT came for ``goal`` in time: say so and bid again."""
        log.info(
            "performer %s: no CONFIRM/REJECT for %s within %g s; bidding again",
            self.node_name,
            goal.full_name,
            self.commit_timeout,
        )
        self._committed = None

    def _on_action_msg(self, msg: object) -> None:
        # The class compared first: isinstance is a call, and every message comes here.
        if (
            msg.__class__ is not ActionExecution and not isinstance(msg, ActionExecution)
        ) or not self._running:
            return
        kind = msg.type
        if kind is _REQUEST:
            self._on_request(msg)
        elif msg.node_id != self.node_name:
            return
        elif kind is _CONFIRM:
            # committed, same_goal and full_name, inlined: once per executed action
            goal = self._committed
            if goal is None:
                return
            loop = self._loop
            if loop is not None and loop.time() >= self._commit_deadline:
                self._lapse(goal)
                return
            rid = msg.request_id
            arguments = msg.arguments
            if (
                (goal.request_id and rid and goal.request_id != rid)
                or goal.action != msg.action
                or goal.arguments
                != (arguments if arguments.__class__ is tuple else tuple(arguments))
            ):
                return  # not (or no longer) committed to this request
            self._committed = None  # _release_commitment, inlined
            self.goal = goal
            self.completion = 0.0
            self.executed += 1
            self.state = _RUNNING
            self._cancelling = False
            self._task = asyncio.get_running_loop().create_task(
                self._run_goal(goal),
                name=f"{self.node_name}:({' '.join((goal.action, *goal.arguments))})",
            )
            self._publish_status()
        elif kind is _REJECT:
            # same_goal and the release, inlined: every bidder but one comes here. The
            # commitment is read without its deadline: a lapsed one ends here either way.
            committed = self._committed
            if committed is not None:
                rid = msg.request_id
                if (
                    not (committed.request_id and rid and committed.request_id != rid)
                    and committed.action == msg.action
                    and committed.arguments == tuple(msg.arguments)
                ):
                    self._committed = None
        elif kind is _CANCEL:
            self._on_cancel_msg(msg)

    def _on_request(self, msg: object, routed: bool = False) -> None:
        """A REQUEST: answer it with a RESPONSE when idle, serving it and bidding.

        ``routed``: handed by the hub's router under this performer's REQUEST route
        keys (see :func:`~plansys_bridge.performers.listening.listen`), which only
        hands over the REQUESTs of served actions whose specialised arguments match:
        that check is then not made again."""
        # Also the subscriber of the REQUEST route keys, so it checks what
        # _on_action_msg would: an auction message, a REQUEST, the performer running.
        if (
            (msg.__class__ is not ActionExecution and not isinstance(msg, ActionExecution))
            or msg.type is not _REQUEST
            or not self._running
        ):
            return
        # The cheap refusals come first, read off the message: a busy performer, or
        # one whose specialised arguments do not fit, builds nothing. The goal itself
        # is shared by every performer handed the same REQUEST (goal_of).
        if self._committed is not None:
            committed = self.committed
            if committed is not None:
                if committed == goal_of(msg):
                    # our RESPONSE may have been lost
                    self._send(_RESPONSE, committed, bid=self._committed_bid)
                return
        if self._task is not None:
            return
        if self._own_serves:
            goal = goal_of(msg)
            if not self.serves(goal):
                return
        else:
            if not routed:
                spec = self.actions.get(msg.action)
                if spec is None or (spec and not arguments_match(spec, msg.arguments)):
                    return
            last_msg, goal = last_request[0]  # goal_of's look-up, inlined
            if last_msg is not msg:
                goal = goal_of(msg)
        if self._own_accepts or self._own_bid or self.bid_costs:
            try:
                if self._own_accepts and not self.accepts(goal):
                    return
                learned = (
                    self.bid_costs.cost(goal.action, goal.arguments) if self.bid_costs else None
                )
                cost = learned if learned is not None else self.bid(goal)
            except Exception:
                log.exception(
                    "performer %s: bid/accepts for %s raised", self.node_name, goal.full_name
                )
                return
            if cost is not None and (cost != cost or cost == _INF):  # NaN or inf
                return
        else:
            cost = None  # the base class's bid, not asked
        self._committed = goal
        self._committed_bid = cost
        loop = self._loop or asyncio.get_running_loop()
        self._commit_deadline = loop.time() + self.commit_timeout
        # _respond, inlined: every bidder of every auction comes by
        self._out(
            _ACTIONS_HUB,
            action_execution(
                _RESPONSE,
                self.node_name,
                goal.action,
                goal.arguments,
                bid=cost,
                request_id=goal.request_id,
            ),
        )

    def _release_commitment(self) -> None:
        self._committed = None

    def _on_cancel_msg(self, msg: ActionExecution) -> None:
        committed = self.committed
        if committed is not None and same_goal(committed, msg):
            self._release_commitment()
            return
        goal, task = self.goal, self._task
        if goal is None or task is None or not same_goal(goal, msg) or self._cancelling:
            return
        self._cancelling = True
        task.cancel()

    async def _run_goal(self, goal: ActionGoal) -> None:
        try:
            try:
                status = await self.execute(goal)
            except asyncio.CancelledError:
                if not self._cancelling:
                    raise
                await self._after_cancel(goal)
            except ActionFailed as exc:
                self._finish(goal, False, str(exc) or "failed")
            except Exception as exc:
                log.exception("performer %s: %s raised", self.node_name, goal.full_name)
                self._finish(goal, False, f"{type(exc).__name__}: {exc}")
            else:
                if self._plain_finish:
                    # _finish and _send, inlined: once per executed action
                    self._out(
                        _ACTIONS_HUB,
                        action_execution(
                            _FINISH,
                            self.node_name,
                            goal.action,
                            goal.arguments,
                            success=True,
                            completion=1.0,
                            status=status if status else "succeeded",
                            request_id=goal.request_id,
                        ),
                    )
                else:
                    self._finish(goal, True, status if status else "succeeded")
        finally:
            self._task = None
            self.goal = None
            self._cancelling = False
            if self._running:
                self.state = _READY
                self._publish_status()

    async def _after_cancel(self, goal: ActionGoal) -> None:
        try:
            await self.on_cancel(goal)
        except Exception:
            log.exception("performer %s: on_cancel(%s) raised", self.node_name, goal.full_name)

    def _finish(self, goal: ActionGoal, success: bool, status: str) -> None:
        completion = 1.0 if success else self.completion
        self._send(
            ExecutionType.FINISH, goal, success=success, completion=completion, status=status
        )

    def _send(
        self,
        kind: ExecutionType,
        goal: ActionGoal,
        *,
        success: bool = False,
        completion: float = 0.0,
        status: str = "",
        bid: float | None = None,
    ) -> None:
        self._out(
            _ACTIONS_HUB,
            action_execution(
                kind,
                self.node_name,
                goal.action,
                goal.arguments,
                success=success,
                completion=completion,
                status=status,
                bid=bid,
                request_id=goal.request_id,
            ),
        )
