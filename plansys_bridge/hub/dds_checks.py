"""Checks a message received from DDS must pass before anybody uses it.

Any DDS node of the domain can write on the hub's topics. Decoding already refuses
what the ``.msg`` types allow but PlanSys2's protocol does not (a constant outside the
message's own, a non-finite number; see :mod:`plansys_bridge.hub.dds_convert`). The
checks here add ranges (completion within 0..1, no negative durations or bids) and
what only the mission knows: the domain's actions and their arity, and the plans this
executor runs (a request id ``<plan_id>/<plan>/<step>`` or an executing plan naming
another plan belongs to some other executor on the domain). A check returns the
reason to drop a message, or None; :class:`~plansys_bridge.hub.dds.DdsTransport` drops it with one
log line naming the topic and the writer, so a foreign node can neither crash the
executor nor reach the knowledge.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Set

from plansys_bridge.hub import messages as hm

__all__ = ["SampleCheck", "check_sample", "domain_check", "plan_of"]

SampleCheck = Callable[[str, object], "str | None"]
"""``check(hub_topic, message)`` -> why the message must be dropped, or None."""


def _fraction(name: str, value: float) -> str | None:
    return None if 0.0 <= value <= 1.0 else f"{name} {value!r} is outside 0..1"


def check_sample(topic: str, msg: object) -> str | None:
    """The checks that need no mission: ranges.

    An ``ActionExecution`` (every message of an auction, checked on the reader
    thread) is checked without a call: ``not x >= 0`` holds for NaN too.
    """
    if isinstance(msg, hm.ActionExecution):
        bid = msg.bid
        if bid is not None and not bid >= 0:
            return f"bid {bid!r} is not a cost >= 0"
        completion = msg.completion
        if 0.0 <= completion <= 1.0:
            return None
        return f"completion {completion!r} is outside 0..1"
    if isinstance(msg, hm.ActionExecutionInfo):
        if msg.duration < 0:
            return f"duration {msg.duration!r} is negative"
        return _fraction("completion", msg.completion)
    if isinstance(msg, hm.ExecutingPlan):
        for item in msg.plan.items:
            if item.time < 0 or item.duration < 0:
                return f"plan item {item.action!r} has a negative time or duration"
    return None


def _action_name_and_arity(text: str) -> tuple[str, int] | None:
    words = text.strip().removeprefix("(").removesuffix(")").split()
    if not text.strip().startswith("(") or not words:
        return None
    return words[0], len(words) - 1


def plan_of(request_id: str) -> str:
    """The plan id a request id ``<plan_id>/<plan number>/<step>`` starts with."""
    parts = request_id.rsplit("/", 2)
    return parts[0] if len(parts) == 3 else request_id


def domain_check(actions: Mapping[str, int], plan_ids: Set[str] | None = None) -> SampleCheck:
    """:func:`check_sample` plus the domain's action names and arities (name -> arity).

    With ``plan_ids`` (the plans this process executes, filled as they start), a
    project message naming another plan is dropped too: it belongs to some other
    executor on the domain. Before the first plan starts nothing is known, nothing
    is dropped for it.
    """

    def other_plan(plan_id: str) -> str | None:
        if plan_ids and plan_id not in plan_ids:
            return f"plan id {plan_id!r} is not a plan of this executor"
        return None

    def unknown(action: str, arguments: int | None) -> str | None:
        arity = actions.get(action)
        if arity is None:
            return f"unknown action {action!r} (the domain has {', '.join(sorted(actions))})"
        if arguments is not None and arguments != arity:
            return f"action {action!r} takes {arity} arguments, got {arguments}"
        return None

    def check(topic: str, msg: object) -> str | None:
        reason = check_sample(topic, msg)
        if reason is not None:
            return reason
        if isinstance(msg, hm.ActionExecution) and msg.request_id:
            reason = other_plan(plan_of(msg.request_id))
        if isinstance(msg, hm.ExecutingPlan) and msg.plan_id:
            reason = other_plan(msg.plan_id)
        if reason is not None:
            return reason
        if isinstance(msg, hm.ActionExecution | hm.ActionExecutionInfo):
            return unknown(msg.action, len(msg.arguments))
        if isinstance(msg, hm.ActionPerformerStatus):
            reason = unknown(msg.action, None)
            arity = actions.get(msg.action, 0)
            if reason is None and len(msg.specialized_arguments) > arity:
                reason = f"{len(msg.specialized_arguments)} specialised arguments for {arity}"
            return reason
        if isinstance(msg, hm.ExecutingPlan):
            for item in msg.plan.items:
                parsed = _action_name_and_arity(item.action)
                if parsed is None:
                    return f"plan item {item.action!r} is not an action like (move r1 a b)"
                reason = unknown(*parsed)
                if reason is not None:
                    return reason
        return None

    return check
