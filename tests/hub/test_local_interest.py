"""A DDS transport delivers its own messages at home only when somebody there wants
them, and never loses one a local subscriber could want."""

from __future__ import annotations

import asyncio

import pytest

from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.local_interest import LocalInterest
from plansys_bridge.hub.routing import TopicRouter, performer_keys

REJECT_P1 = hm.action_execution(hm.ExecutionType.REJECT, "p1", "move", ("r", "a", "b"))
REJECT_P2 = hm.action_execution(hm.ExecutionType.REJECT, "p2", "move", ("r", "a", "b"))


class _Sub:
    closed = False

    def close(self) -> None:
        self.closed = True


def test_a_router_wants_what_it_would_deliver() -> None:
    router = TopicRouter(hm.Topics.ACTIONS_HUB)
    assert not router.wants(REJECT_P1)
    keyed = router.add(lambda m: None, performer_keys("p1", ["move"]))
    assert router.wants(REJECT_P1) and not router.wants(REJECT_P2)
    assert router.wants(object())  # a message the router cannot place goes to everybody
    keyed.close()
    router.add(lambda m: None, None)
    assert router.wants(REJECT_P2)


def test_a_subscriber_without_a_filter_wants_everything_until_it_leaves() -> None:
    interest = LocalInterest()
    topic = hm.Topics.ACTIONS_HUB
    assert interest.wanted(topic, REJECT_P1)  # nobody to ask: deliver (to nobody)
    picky = interest.track(topic, _Sub(), lambda m: m is REJECT_P1)
    assert interest.wanted(topic, REJECT_P1) and not interest.wanted(topic, REJECT_P2)
    everything = interest.track(topic, inner := _Sub(), None)
    assert interest.wanted(topic, REJECT_P2)
    everything.close()
    assert inner.closed
    assert not interest.wanted(topic, REJECT_P2)
    picky.close()
    assert interest.wanted(topic, REJECT_P2)


def test_own_messages_reach_the_local_subscribers_they_concern() -> None:
    pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")
    import random

    from plansys_bridge.hub.dds import DdsTransport

    async def main() -> tuple[list[object], list[object]]:
        transport = DdsTransport(random.SystemRandom().randint(1, 232))
        hub = Hub(transport)
        await hub.start()
        try:
            mine: list[object] = []
            everything: list[object] = []
            hub.subscribe(hm.Topics.ACTIONS_HUB, mine.append, keys=performer_keys("p1", ["move"]))
            hub.publish(hm.Topics.ACTIONS_HUB, REJECT_P2)  # for nobody here
            hub.publish(hm.Topics.ACTIONS_HUB, REJECT_P1)
            await asyncio.sleep(0.05)
            hub.subscribe(hm.Topics.ACTIONS_HUB, everything.append)
            hub.publish(hm.Topics.ACTIONS_HUB, REJECT_P2)
            await asyncio.sleep(0.05)
            return mine, everything
        finally:
            await hub.close()

    mine, everything = asyncio.run(main())
    assert mine == [REJECT_P1]
    assert everything == [REJECT_P2]
