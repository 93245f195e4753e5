"""A ``publish_many`` batch on ``actions_hub`` reaches the hub's router in one call
(``dispatch_many``): every subscriber gets what ``publish`` one message at a time
would have given it, in the same order, subscribers closing meanwhile included."""

from __future__ import annotations

import asyncio
from collections.abc import Hashable
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics, action_execution
from plansys_bridge.hub.routing import client_keys
from plansys_bridge.hub.transport import InProcessTransport, Subscription

KEYS: list[list[Hashable] | None] = [
    None,
    [("node", "a")],
    [("node", "b")],
    [("action", "move")],
    client_keys("q", "move", ["r1"]),
]
MESSAGES = st.builds(
    lambda kind, node, rid: action_execution(kind, node, "move", ("r1",), request_id=rid),
    st.sampled_from(ExecutionType),
    st.sampled_from(["a", "b", ""]),
    st.sampled_from(["", "q"]),
)
STEPS = st.lists(
    st.one_of(
        st.tuples(st.sampled_from(["one", "many"]), st.lists(MESSAGES, max_size=5)),
        st.tuples(st.just("subscribe"), st.integers(0, len(KEYS) - 1)),
        st.tuples(st.just("close"), st.integers(0, 7)),
        st.tuples(st.just("yield")),
    ),
    max_size=14,
)


async def _deliveries(steps: list[tuple[Any, ...]], batched: bool) -> list[Any]:
    hub = Hub(InProcessTransport(), VirtualClock())
    await hub.start()
    got: list[Any] = []
    subs: list[Subscription] = []

    def heard(name: int, msg: object) -> None:
        got.append((name, msg))
        # A CANCEL heard closes the last subscriber, mid-batch (maybe a later one
        # that the same message is for).
        if isinstance(msg, ActionExecution) and msg.type is ExecutionType.CANCEL:
            subs[-1].close()

    for step in steps:
        kind = step[0]
        if kind == "subscribe":
            name = len(subs)
            subs.append(
                hub.subscribe(Topics.ACTIONS_HUB, lambda m, n=name: heard(n, m), keys=KEYS[step[1]])
            )
        elif kind == "close" and subs:
            subs[step[1] % len(subs)].close()
        elif kind == "many" and batched:
            hub.publish_many(Topics.ACTIONS_HUB, step[1])
        elif kind in ("one", "many"):
            for msg in step[1]:
                hub.publish(Topics.ACTIONS_HUB, msg)
        else:
            got.append("yield")
            await asyncio.sleep(0)
    await asyncio.sleep(0)
    await hub.close()
    return got


@settings(max_examples=300, deadline=None)
@given(steps=STEPS)
def test_a_batch_reaches_every_subscriber_as_one_message_at_a_time_would(
    steps: list[tuple[Any, ...]],
) -> None:
    one_by_one = run(_deliveries(steps, batched=False), VirtualClock())
    batched = run(_deliveries(steps, batched=True), VirtualClock())
    assert batched == one_by_one
