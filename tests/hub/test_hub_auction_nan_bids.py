"""Bids that are not numbers: a performer costing NaN or inf does not answer, and a
RESPONSE whose bid is NaN counts as no cost (it loses to any number)."""

from __future__ import annotations

import asyncio
import math

import pytest

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ExecutionType, Topics, action_execution
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionGoal, ActionPerformer, PerformerContext


class Costing(ActionPerformer):
    def __init__(self, *a: object, cost: float | None, **kw: object) -> None:
        super().__init__(*a, **kw)  # type: ignore[arg-type]
        self.cost = cost

    def bid(self, goal: ActionGoal) -> float | None:
        return self.cost

    async def execute(self, goal: ActionGoal) -> str | None:
        return None


@pytest.mark.parametrize(
    ("cost", "answers"),
    [(math.nan, False), (math.inf, False), (-math.inf, True), (3.0, True), (None, True)],
)
def test_a_performer_costing_nan_or_inf_does_not_answer(cost: float | None, answers: bool) -> None:
    clock = VirtualClock()

    async def main() -> list[object]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        sent: list[object] = []
        hub.subscribe(Topics.ACTIONS_HUB, sent.append)
        p = Costing(PerformerContext(hub, clock), "p", {"move": []}, cost=cost)
        await p.start()
        hub.publish(
            Topics.ACTIONS_HUB,
            action_execution(ExecutionType.REQUEST, "", "move", ("a",), request_id="q"),
        )
        await asyncio.sleep(0)
        await asyncio.sleep(0)
        await p.stop()
        await hub.close()
        return [m for m in sent if getattr(m, "type", None) is ExecutionType.RESPONSE]

    assert len(run(main(), clock)) == (1 if answers else 0)


def test_a_nan_bid_loses_to_a_number_and_ties_with_no_bid_by_arrival() -> None:
    clock = VirtualClock()

    async def auction(bids: list[float | None]) -> str:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        client = ActionClient(
            hub, "move", ("a",), request_id="q", policy=AuctionPolicy(selection="best_bid")
        )
        task = asyncio.get_running_loop().create_task(client.run())
        await asyncio.sleep(0)
        for i, bid in enumerate(bids):
            hub.publish(
                Topics.ACTIONS_HUB,
                action_execution(
                    ExecutionType.RESPONSE, f"n{i}", "move", ("a",), bid=bid, request_id="q"
                ),
            )
        await asyncio.sleep(0.1)
        winner = client.performer
        client.cancel()
        await task
        await hub.close()
        return winner

    async def main() -> list[str]:
        return [
            await auction([math.nan, 5.0]),
            await auction([math.nan, None]),
            await auction([None, math.nan]),
        ]

    assert run(main(), clock) == ["n1", "n0", "n0"]
