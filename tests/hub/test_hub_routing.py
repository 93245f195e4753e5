"""Routing in the hub: each auction message reaches exactly the subscribers it concerns,
heartbeats feed one liveness table, subscribers without keys still hear everything."""

from __future__ import annotations

import asyncio
import dataclasses
from collections import Counter
from typing import Any

import pytest
from hub_counting import Counting

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionPerformerStatus,
    ExecutionType,
    PerformerState,
    Topics,
    action_execution,
)
from plansys_bridge.hub.routing import client_keys, performer_keys
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext

T = ExecutionType


def _msg(
    kind: ExecutionType, node: str = "", rid: str = "", action: str = "move"
) -> ActionExecution:
    return ActionExecution(kind, node, action, ("r1", "a", "b"), request_id=rid)


def test_each_kind_of_auction_message_reaches_exactly_its_subscribers() -> None:
    clock = VirtualClock()

    async def main() -> dict[str, list[str]]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        got: dict[str, list[str]] = {}

        def listen(name: str, keys: Any) -> None:
            def on_msg(m: object) -> None:
                text = (
                    f"{m.type.name}:{m.node_id}:{m.request_id}"
                    if isinstance(m, ActionExecution)
                    else "other"
                )
                got.setdefault(name, []).append(text)

            hub.subscribe(Topics.ACTIONS_HUB, on_msg, keys=keys)

        listen("everything", None)
        listen("mover_a", performer_keys("a", ["move"]))
        listen("mover_b", performer_keys("b", ["move", "pick"]))
        listen("picker_c", performer_keys("c", ["pick"]))
        listen("client_1", client_keys("1", "move", ("r1", "a", "b")))
        listen("client_2", client_keys("2", "move", ("r1", "a", "b")))
        for m in (
            _msg(T.REQUEST, rid="1"),
            _msg(T.RESPONSE, "a", "1"),
            _msg(T.RESPONSE, "b", "1"),
            _msg(T.CONFIRM, "a", "1"),
            _msg(T.REJECT, "b", "1"),
            _msg(T.FEEDBACK, "a", "1"),
            _msg(T.FINISH, "a", "1"),
            _msg(T.CANCEL, "c", "2"),
            _msg(T.RESPONSE, "x", ""),  # no request id: by the action text
            _msg(T.REQUEST, rid="3", action="pick"),
        ):
            hub.publish(Topics.ACTIONS_HUB, m)
        hub.publish(Topics.ACTIONS_HUB, "not an auction message")  # unroutable: everybody
        await asyncio.sleep(0)
        await hub.close()
        return got

    got = run(main(), clock)
    assert got["mover_a"] == ["REQUEST::1", "CONFIRM:a:1", "other"]
    assert got["mover_b"] == ["REQUEST::1", "REJECT:b:1", "REQUEST::3", "other"]
    assert got["picker_c"] == ["CANCEL:c:2", "REQUEST::3", "other"]
    assert got["client_1"] == [
        *("RESPONSE:a:1", "RESPONSE:b:1", "FEEDBACK:a:1", "FINISH:a:1", "RESPONSE:x:", "other")
    ]
    assert got["client_2"] == ["RESPONSE:x:", "other"]
    assert len(got["everything"]) == 11


def test_an_auction_among_many_bidders_hands_each_performer_only_its_own_messages() -> None:
    clock = VirtualClock()

    async def main() -> tuple[list[Counting], list[Counting], int]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        ctx = PerformerContext(hub, clock)
        movers = [Counting(ctx, f"m{i}", {"move": []}) for i in range(20)]
        pickers = [Counting(ctx, f"p{i}", {"pick": []}) for i in range(20)]
        for p in (*movers, *pickers):
            await p.start()
        policy = AuctionPolicy(selection="best_bid", bid_window=0.01)
        outcome = await ActionClient(hub, "move", ("r1", "a", "b"), policy=policy).run()
        assert outcome.success
        await asyncio.sleep(0)
        for p in (*movers, *pickers):
            await p.stop()
        status_subscribers = hub.transport.subscriber_count(Topics.PERFORMERS_STATUS)  # type: ignore[attr-defined]
        await hub.close()
        return movers, pickers, status_subscribers

    movers, pickers, status_subscribers = run(main(), clock)
    assert all(sum(p.heard.values()) == 0 for p in pickers)
    winner = [p for p in movers if p.executed]
    assert len(winner) == 1
    assert winner[0].heard == Counter({"REQUEST": 1, "CONFIRM": 1})
    for p in movers:
        if p is not winner[0]:
            assert p.heard == Counter({"REQUEST": 1, "REJECT": 1})
    assert status_subscribers == 1  # the hub's liveness table, not one per client


def test_heartbeats_feed_one_table_that_many_clients_share() -> None:
    clock = VirtualClock()

    async def main() -> tuple[int, PerformerState | None, float | None, list[bool]]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        ctx = PerformerContext(hub, clock)
        workers = [Counting(ctx, f"w{i}", {"move": [f"r{i}"]}) for i in range(5)]
        for w in workers:
            await w.start()
        clients = [ActionClient(hub, "move", (f"r{i}", "a", "b")) for i in range(5)]
        tasks = [asyncio.ensure_future(c.run()) for c in clients]
        await asyncio.sleep(0.5)
        table = hub.liveness
        running = table.state("w0", "move")
        heard = table.last_running("w0")
        outcomes = await asyncio.gather(*tasks)
        for w in workers:
            await w.stop()
        await hub.close()
        return table.heartbeats, running, heard, [o.success for o in outcomes]

    heartbeats, running, heard, successes = run(main(), clock)
    assert successes == [True] * 5
    assert running is PerformerState.RUNNING and heard == 0.0
    # each state change of 5 performers, taken once, not once per client
    assert 10 <= heartbeats <= 20


def test_a_freed_performer_is_asked_again_at_once() -> None:
    """A client whose only performer is busy asks again the moment the table sees
    it go READY, not at its next periodic REQUEST."""
    clock = VirtualClock()

    async def main() -> list[float]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        ctx = PerformerContext(hub, clock)
        worker = Counting(ctx, "w", {"move": []}, heartbeat_period=10.0)
        await worker.start()
        requests: list[float] = []

        def on_msg(m: object) -> None:
            if isinstance(m, ActionExecution) and m.type is T.REQUEST:
                requests.append(asyncio.get_running_loop().time())

        hub.subscribe(Topics.ACTIONS_HUB, on_msg)
        policy = AuctionPolicy(retry_period=5.0)
        first = asyncio.ensure_future(ActionClient(hub, "move", ("a",), policy=policy).run())
        await asyncio.sleep(0.1)
        second = await ActionClient(hub, "move", ("b",), policy=policy).run()
        assert second.success and (await first).success
        await worker.stop()
        await hub.close()
        return requests

    requests = run(main(), clock)
    assert requests == [0.0, 0.1, 1.0]  # the worker finished at 1.0: asked at once


def test_heartbeats_of_an_unknown_sender_are_ignored_by_the_table() -> None:
    clock = VirtualClock()

    async def main() -> int:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        table = hub.liveness
        hub.publish(Topics.PERFORMERS_STATUS, "garbage")
        hub.publish(
            Topics.PERFORMERS_STATUS,
            ActionPerformerStatus(0.0, PerformerState.READY, "move", (), "n"),
        )
        await asyncio.sleep(0)
        await hub.close()
        return table.heartbeats

    assert run(main(), clock) == 1


def test_the_fast_message_factory_makes_the_same_message_as_the_dataclass() -> None:
    fast = action_execution(
        ExecutionType.FINISH,
        "n1",
        "move",
        ("r", "a"),
        success=True,
        completion=0.5,
        status="half",
        bid=2.5,
        request_id="p/0/3",
    )
    slow = ActionExecution(
        type=ExecutionType.FINISH,
        node_id="n1",
        action="move",
        arguments=("r", "a"),
        success=True,
        completion=0.5,
        status="half",
        bid=2.5,
        request_id="p/0/3",
    )
    assert fast == slow and hash(fast) == hash(slow) and repr(fast) == repr(slow)
    assert action_execution(ExecutionType.REQUEST, "", "move", ()) == ActionExecution(
        type=ExecutionType.REQUEST, node_id="", action="move"
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.status = "changed"  # type: ignore[misc]
