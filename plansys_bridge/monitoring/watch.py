"""Follow a mission from its hub traffic alone: plans, actions, auctions, performers.

The progress lines of ``run``, the live table on a terminal, ``monitor`` over DDS
and the pictures drawn from a recording all need the same view of a mission, and
all they can rely on is what goes over the hub (an executor in another process is
only reachable that way). :class:`MissionWatch` turns messages into that view:

* ``executing_plan``: a plan starts (the first of a ``plan_id``, or a replan);
* ``action_execution_info``: an action's status, completion and message;
* ``actions_hub``: RESPONSEs (bids) and the CONFIRM naming the auction's winner;
* ``performers_status``: heartbeats (state, action served, when last seen);
* ``problem_expert/knowledge``: the knowledge after each change;
* ``dot_graph``: the coloured plan graph (the last one of each plan is kept).

Each change is also handed to a listener as a :class:`WatchEvent`, so a view can
print it as it happens. :meth:`MissionWatch.feed` takes a message for a topic
directly, which is how a recording is replayed into the same view.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.messages import ActionStatus, ExecutionType, PerformerState, Topics

__all__ = ["ActionView", "MissionWatch", "PerformerView", "PlanView", "WatchEvent"]

EventKind = Literal["plan", "status", "feedback", "assigned", "performer", "knowledge", "dot"]


@dataclass
class ActionView:
    """One action of one plan, as the hub traffic shows it."""

    text: str
    plan_number: int
    planned_start: float
    planned_duration: float
    status: ActionStatus = ActionStatus.NOT_EXECUTED
    completion: float = 0.0
    message: str = ""
    performer: str = ""
    bids: int = 0
    start: float | None = None
    """Mission time of the first EXECUTING status."""
    end: float | None = None
    """Mission time of the SUCCEEDED, FAILED or CANCELLED status."""

    @property
    def finished(self) -> bool:
        return self.status in (ActionStatus.SUCCEEDED, ActionStatus.FAILED, ActionStatus.CANCELLED)


@dataclass
class PlanView:
    """A plan as it started: ``number`` counts plans of the mission from 0."""

    number: int
    plan_id: str
    stamp: float
    items: tuple[hm.PlanItem, ...]
    actions: list[ActionView] = field(default_factory=list)

    @property
    def replan(self) -> bool:
        return self.number > 0


@dataclass
class PerformerView:
    name: str
    state: PerformerState
    actions: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """Action -> its specialised arguments (empty: any)."""
    last_seen: float = 0.0
    """The stamp of its last heartbeat (the sender's clock)."""
    heard: float = 0.0
    """When its last heartbeat arrived, on this watch's clock (a performer in another
    process stamps with its own clock, so "seen N s ago" is measured with this)."""
    current: str = ""
    """Text of the action it was confirmed for and has not finished."""


@dataclass(frozen=True)
class WatchEvent:
    kind: EventKind
    stamp: float
    action: ActionView | None = None
    plan: PlanView | None = None
    performer: PerformerView | None = None
    knowledge: hm.Knowledge | None = None


Listener = Callable[[WatchEvent], None]

TOPICS = (
    Topics.EXECUTING_PLAN,
    Topics.ACTION_EXECUTION_INFO,
    Topics.ACTIONS_HUB,
    Topics.PERFORMERS_STATUS,
    Topics.KNOWLEDGE,
    Topics.DOT_GRAPH,
)


def _text(action: str, arguments: tuple[str, ...] | list[str]) -> str:
    return "(" + " ".join([action, *arguments]) + ")"


class MissionWatch:
    """The view of a mission built from hub messages (see module docs)."""

    def __init__(self, clock: Callable[[], float], listener: Listener | None = None) -> None:
        self.clock = clock
        self.listener = listener
        self.plans: list[PlanView] = []
        self.performers: dict[str, PerformerView] = {}
        self.knowledge: hm.Knowledge | None = None
        self.dots: dict[str, str] = {}
        """DOT graph name (``plan-1/0``: plan id / plan number) -> its last DOT text."""
        self._current: dict[str, list[ActionView]] = {}
        """Action text -> its views in the newest plan that has it (a plan may run
        the same action twice: ``(move r a b)`` early and again later)."""
        self._bidders: dict[str, set[str]] = {}
        self._subscriptions: list[Any] = []

    # ------------------------------------------------------------ wiring

    def attach(self, hub: Any) -> MissionWatch:
        """Subscribe to every topic the view needs on ``hub``."""
        for topic in TOPICS:
            self._subscriptions.append(hub.subscribe(topic, lambda msg, t=topic: self.feed(t, msg)))
        return self

    def close(self) -> None:
        for sub in self._subscriptions:
            sub.close()
        self._subscriptions.clear()

    def feed(self, topic: str, msg: object, stamp: float | None = None) -> None:
        """Take one message of ``topic`` (stamped ``stamp``, default: the clock now)."""
        now = self.clock() if stamp is None else stamp
        if isinstance(msg, hm.ExecutingPlan):
            self._on_plan(msg, now)
        elif isinstance(msg, hm.ActionExecutionInfo):
            self._on_info(msg, now)
        elif isinstance(msg, hm.ActionExecution):
            self._on_auction(msg, now)
        elif isinstance(msg, hm.ActionPerformerStatus):
            self._on_heartbeat(msg, now)
        elif isinstance(msg, hm.Knowledge):
            self.knowledge = msg
            self._emit(WatchEvent("knowledge", now, knowledge=msg))
        elif isinstance(msg, hm.DotGraph):
            first = msg.text.split("\n", 1)[0]
            name = first.split('"')[1] if first.count('"') >= 2 else msg.plan_id
            self.dots[name] = msg.text
            self._emit(WatchEvent("dot", now))

    # ------------------------------------------------------------ queries

    @property
    def actions(self) -> list[ActionView]:
        """Every action of every plan, in plan order."""
        return [a for plan in self.plans for a in plan.actions]

    def action(self, text: str) -> ActionView | None:
        """The view of ``text`` in the newest plan (its first unfinished one)."""
        return self._find(text, ActionStatus.EXECUTING)

    def _find(self, text: str, status: ActionStatus) -> ActionView | None:
        """Which of the same-text actions a message about ``text`` is about: one
        already in ``status`` (feedback), else the first one not finished."""
        views = self._current.get(text, [])
        for view in views:
            if view.status == status and not view.finished:
                return view
        for view in views:
            if not view.finished:
                return view
        return views[-1] if views else None

    # ------------------------------------------------------------ handlers

    def _emit(self, event: WatchEvent) -> None:
        if self.listener is not None:
            self.listener(event)

    def _on_plan(self, msg: hm.ExecutingPlan, now: float) -> None:
        plan = PlanView(len(self.plans), msg.plan_id, now, tuple(msg.plan.items))
        fresh: dict[str, list[ActionView]] = {}
        for item in plan.items:
            view = ActionView(item.action, plan.number, item.time, item.duration)
            plan.actions.append(view)
            fresh.setdefault(item.action, []).append(view)
        self._current.update(fresh)
        self.plans.append(plan)
        self._emit(WatchEvent("plan", now, plan=plan))

    def _on_info(self, info: hm.ActionExecutionInfo, now: float) -> None:
        text = info.action_full_name or _text(info.action, info.arguments)
        view = self._find(text, info.status)
        if view is None:  # an action of a plan started before the watch was
            view = ActionView(text, -1, 0.0, info.duration)
            self._current[text] = [view]
        changed = info.status != view.status
        view.completion = info.completion
        view.message = info.message_status
        if not changed:
            self._emit(WatchEvent("feedback", now, action=view))
            return
        view.status = info.status
        if info.status == ActionStatus.EXECUTING and view.start is None:
            view.start = info.start_stamp or now
        if view.finished:
            view.end = now
            performer = self.performers.get(view.performer)
            if performer is not None and performer.current == text:
                performer.current = ""
        self._emit(WatchEvent("status", now, action=view))

    def _on_auction(self, msg: hm.ActionExecution, now: float) -> None:
        text = _text(msg.action, msg.arguments)
        key = msg.request_id or text
        if msg.type is ExecutionType.REQUEST:
            self._bidders.setdefault(key, set())
        elif msg.type is ExecutionType.RESPONSE:
            self._bidders.setdefault(key, set()).add(msg.node_id)
        elif msg.type is ExecutionType.CONFIRM:
            view = self._find(text, ActionStatus.EXECUTING)
            if view is None:
                return
            view.performer = msg.node_id
            view.bids = len(self._bidders.pop(key, set()) | {msg.node_id})
            performer = self.performers.get(msg.node_id)
            if performer is not None:
                performer.current = text
            self._emit(WatchEvent("assigned", now, action=view))

    def _on_heartbeat(self, msg: hm.ActionPerformerStatus, now: float) -> None:
        name = msg.node_name or msg.action
        view = self.performers.get(name)
        fresh = view is None
        if view is None:
            view = self.performers[name] = PerformerView(name, msg.state)
        changed = fresh or view.state != msg.state
        view.state = msg.state
        if msg.action:
            view.actions[msg.action] = tuple(msg.specialized_arguments)
        view.last_seen = msg.status_stamp or now
        view.heard = now
        if changed:
            self._emit(WatchEvent("performer", now, performer=view))
