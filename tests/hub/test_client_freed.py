"""An ended auction client is freed as soon as nobody holds it, without the cyclic
collector: a plan of thousands of actions makes one per action, and clients kept
alive by their own cycles (the router's callback, the executor's partials) were
most of what the collector went through again and again while a plan ran."""

from __future__ import annotations

import asyncio
import gc
import weakref
from collections.abc import Iterator

import pytest

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer


@pytest.fixture
def no_cyclic_collector() -> Iterator[None]:
    gc.collect()
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


@pytest.mark.parametrize("how", ["finish", "give up", "cancel"])
@pytest.mark.usefixtures("no_cyclic_collector")
def test_an_ended_client_is_freed_by_reference_counting(how: str) -> None:
    hub = Hub(InProcessTransport(), VirtualClock())

    async def main() -> tuple[weakref.ref[ActionClient], str]:
        await hub.start()
        performer = SimulatedPerformer(
            PerformerContext(hub, hub.clock), "p", {"move": []}, durations={"move": 3.0}
        )
        if how != "give up":
            await performer.start()
        seen: list[str] = []
        client = ActionClient(
            hub, "move", ["r1"], request_id="f", policy=AuctionPolicy(give_up_after=2.0)
        )
        future = client.start(
            lambda completion, status: seen.append(status),
            confirm_cb=seen.append,
            soon=True,
            settled_cb=lambda: seen.append("settled"),
        )
        if how == "cancel":
            await asyncio.sleep(1.0)  # confirmed, executing
            client.cancel()
        outcome = await future
        gone = weakref.ref(client)
        del client, future
        await asyncio.sleep(10.0)  # long after: the loop holds nothing of it either
        if how != "give up":
            await performer.stop()
        await hub.close()
        return gone, outcome.status

    gone, status = run(main(), hub.clock)
    assert gone() is None, f"{how}: the client outlived its end ({status})"
