"""The hub-wide watch of freed performers (:mod:`plansys_bridge.hub.freed_watch`)
against one watch per client (the general path: what every client had before).

One liveness watcher per action stands for all the clients waiting for that action;
with one per client the hub must see the same messages at the same instants in the
same order, and every action must end the same way.
"""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings

from plansys_bridge.hub import auction
from plansys_bridge.hub.freed_watch import FreedWatch, watch_of
from plansys_bridge.hub.liveness import LivenessTable
from plansys_bridge.hub.messages import ActionPerformerStatus, PerformerState
from tests.hub.test_hub_auction_properties import SCENARIOS, _simulate


def _observe(
    performers: list[dict[str, Any]],
    actions: list[tuple[str, float, float | None]],
    policy: auction.AuctionPolicy,
    seed: int,
) -> tuple[list[tuple[float, str]], list[tuple[auction.ActionOutcome, float]]]:
    log, outcomes, _ = _simulate(performers, actions, policy, seed)
    return [(round(t, 9), repr(m)) for t, m in log], outcomes


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(**SCENARIOS)
def test_one_watch_per_hub_behaves_as_one_per_client(
    performers: list[dict[str, Any]],
    actions: list[tuple[str, float, float | None]],
    policy: auction.AuctionPolicy,
    seed: int,
) -> None:
    shared = _observe(performers, actions, policy, seed)
    with pytest.MonkeyPatch.context() as patch:
        # every client makes its own (the class, not the per-hub lookup)
        patch.setattr(auction, "watch_of", FreedWatch)
        patch.setattr(FreedWatch, "last", None)
        own = _observe(performers, actions, policy, seed)
    assert shared[0] == own[0]
    assert shared[1] == own[1]


def test_one_watcher_per_action_tells_the_waiting_clients_in_order() -> None:
    table = LivenessTable()
    watch = watch_of(table)
    told: list[str] = []

    class Client:
        def __init__(self, name: str) -> None:
            self.name = name

        def _on_freed(self, msg: ActionPerformerStatus) -> None:
            told.append(f"{self.name} {msg.node_name}")

    first, second = Client("first"), Client("second")
    waiting = watch.first("move", first)
    waiting[second] = None
    assert len(table._watchers["move"]) == 1

    def status(state: PerformerState) -> ActionPerformerStatus:
        return ActionPerformerStatus(0.0, state, "move", node_name="p1")

    asyncio.run(_feed(table, [status(PerformerState.RUNNING), status(PerformerState.READY)]))
    assert told == ["first p1", "second p1"]
    del waiting[first]
    del waiting[second]
    watch.idle("move")
    assert "move" not in table._watchers and "move" not in watch.waiting


async def _feed(table: LivenessTable, statuses: list[ActionPerformerStatus]) -> None:
    table.on_statuses(statuses)
