"""``publish_many`` delivers what ``publish`` one message at a time would, in the same
order, whether or not a delivery is already scheduled, on every transport."""

from __future__ import annotations

import asyncio

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport

STEPS = st.lists(
    st.tuples(
        st.sampled_from(["one", "many", "yield"]),
        st.sampled_from(["a", "b", "nobody"]),
        st.integers(0, 3),
    ),
    max_size=12,
)


async def _deliveries(steps: list[tuple[str, str, int]], batched: bool) -> list[tuple[str, int]]:
    transport = InProcessTransport()
    hub = Hub(transport)
    await hub.start()
    got: list[tuple[str, int]] = []
    for topic in ("a", "b"):
        hub.subscribe(topic, lambda m, t=topic: got.append((t, m)))  # type: ignore[misc]
    counter = 0
    for kind, topic, n in steps:
        if kind == "yield":
            await asyncio.sleep(0)
            continue
        msgs = list(range(counter, counter + (n if kind == "many" else 1)))
        counter += len(msgs)
        if batched and kind == "many":
            hub.publish_many(topic, msgs)  # type: ignore[arg-type]
        else:
            for m in msgs:
                hub.publish(topic, m)
    await asyncio.sleep(0)
    published = transport.published
    await hub.close()
    return [*got, ("published", published)]


@settings(max_examples=200, deadline=None)
@given(steps=STEPS)
def test_publish_many_delivers_as_publish_one_by_one(steps: list[tuple[str, str, int]]) -> None:
    one_by_one = run(_deliveries(steps, batched=False), VirtualClock())
    batched = run(_deliveries(steps, batched=True), VirtualClock())
    assert batched == one_by_one


def test_a_hub_on_a_transport_without_publish_many_publishes_each() -> None:
    class Plain:
        def __init__(self) -> None:
            self.sent: list[tuple[str, object]] = []

        def publish(self, topic: str, msg: object) -> None:
            self.sent.append((topic, msg))

    plain = Plain()
    hub = Hub(plain)  # type: ignore[arg-type]
    hub.publish_many("t", [1, 2, 3])
    assert plain.sent == [("t", 1), ("t", 2), ("t", 3)]
