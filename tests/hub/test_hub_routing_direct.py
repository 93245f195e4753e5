"""A topic without routes and with one subscriber is delivered to it by the transport
directly: what every subscriber gets, and when, equals delivery through the router."""

from __future__ import annotations

import asyncio
import logging
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub import routing
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport, Subscription

STEPS = st.lists(
    st.tuples(
        st.sampled_from(["subscribe", "subscribe-keyed", "close", "publish", "many", "yield"]),
        st.integers(0, 5),
    ),
    max_size=25,
)


async def _deliveries(steps: list[tuple[str, int]]) -> list[Any]:
    hub = Hub(InProcessTransport(), VirtualClock())
    await hub.start()
    got: list[Any] = []
    subs: list[Subscription] = []
    counter = 0
    for kind, n in steps:
        if kind in ("subscribe", "subscribe-keyed"):
            name = len(subs)
            keys = [("node", "x")] if kind == "subscribe-keyed" else None
            subs.append(hub.subscribe("t", lambda m, s=name: got.append((s, m)), keys=keys))
        elif kind == "close" and subs:
            subs[n % len(subs)].close()
        elif kind == "publish":
            hub.publish("t", counter)
            counter += 1
        elif kind == "many":
            hub.publish_many("t", list(range(counter, counter + n)))
            counter += n
        elif kind == "yield":
            got.append("yield")
            await asyncio.sleep(0)
    await asyncio.sleep(0)
    await hub.close()
    return got


@settings(max_examples=300, deadline=None)
@given(steps=STEPS)
def test_direct_delivery_equals_delivery_through_the_router(steps: list[tuple[str, int]]) -> None:
    direct = run(_deliveries(steps), VirtualClock())
    with pytest.MonkeyPatch.context() as m:
        m.setattr(routing, "redirect", lambda *_: False)  # always the router
        routed = run(_deliveries(steps), VirtualClock())
    assert direct == routed


@pytest.mark.allow_asyncio_errors
def test_a_direct_subscriber_that_raises_is_reported_and_delivery_goes_on(
    caplog: pytest.LogCaptureFixture,
) -> None:
    got: list[object] = []

    def bad(msg: object) -> None:
        got.append(msg)
        raise ValueError("no")

    async def main() -> None:
        hub = Hub(InProcessTransport(), VirtualClock())
        await hub.start()
        hub.subscribe("t", bad)
        hub.publish("t", 1)
        hub.publish("t", 2)
        await asyncio.sleep(0)
        await hub.close()

    with caplog.at_level(logging.ERROR):
        run(main(), VirtualClock())
    assert got == [1, 2]
    raised = [r.getMessage() for r in caplog.records if "raised ValueError" in r.getMessage()]
    assert raised == ["subscriber of 't' raised ValueError: no"] * 2


def test_the_router_is_skipped_only_while_one_subscriber_listens() -> None:
    async def main() -> list[bool]:
        transport = InProcessTransport()
        hub = Hub(transport, VirtualClock())
        await hub.start()
        first = hub.subscribe("t", lambda m: None)
        router_called = []
        router = hub._routers["t"]
        tsub: Any = router.transport_subscription
        router_called.append(tsub.callback == router.dispatch)
        second = hub.subscribe("t", lambda m: None)
        router_called.append(tsub.callback == router.dispatch)
        first.close()
        router_called.append(tsub.callback == router.dispatch)
        second.close()
        router_called.append(tsub.callback == router.dispatch)
        keyed = hub.subscribe("actions_hub", lambda m: None)  # a routed topic
        routed: Any = hub._routers["actions_hub"].transport_subscription
        router_called.append(routed.callback == hub._routers["actions_hub"].dispatch)
        keyed.close()
        await hub.close()
        return router_called

    assert run(main(), VirtualClock()) == [False, True, False, True, True]
