"""ActionClient.start's ``settled_cb`` and ``call_soon``.

``settled_cb()`` stands in for a done callback of the outcome future (the executor's,
once per executed action) without the loop callback the future schedules for one:
it must be called exactly once, with the future already settled, however the client
ends (FINISH, giving up, ``cancel()``, a callback that raises, a first step that
fails); when the client settles the future itself, in the same call, before any
loop callback could run. A cancel from outside reaches it through the client's own
done callback, the future cancelled by then. ``call_soon`` schedules the first step
in place of the loop's ``call_soon``.
"""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy, ClientPhase
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer

ENDINGS = ["finish", "give up", "client cancel", "future cancel", "confirm raises", "closed"]


def _ending(how: str) -> tuple[Any, list[tuple[bool, bool]], ClientPhase]:
    """Run one client to the ending ``how``; returns how its future ended, what the
    settled callback saw at each call (the future done, a done callback of the
    future already run) and the client's phase."""
    hub = Hub(InProcessTransport(), VirtualClock())

    async def main() -> tuple[Any, list[tuple[bool, bool]], ClientPhase]:
        await hub.start()
        performer = SimulatedPerformer(
            PerformerContext(hub, hub.clock), "p", {"move": []}, durations={"move": 3.0}
        )
        if how not in ("give up", "closed"):
            await performer.start()
        calls: list[tuple[bool, bool]] = []
        scheduled: list[bool] = []

        def refuse(_node: str) -> None:
            raise RuntimeError("confirm refused")

        client = ActionClient(
            hub, "move", ["r1"], request_id="s", policy=AuctionPolicy(give_up_after=2.0)
        )
        if how == "closed":
            await hub.close()
        future = client.start(
            confirm_cb=refuse if how == "confirm raises" else None,
            soon=True,
            settled_cb=lambda: calls.append((future.done(), bool(scheduled))),
        )
        future.add_done_callback(lambda _f: scheduled.append(True))
        if how in ("client cancel", "future cancel"):
            await asyncio.sleep(1.0)  # confirmed, executing
            if how == "client cancel":
                client.cancel()
            else:
                future.cancel()
        ended: Any
        try:
            ended = await future
        except asyncio.CancelledError:
            ended = "cancelled"
        except Exception as exc:
            ended = repr(exc)
        await asyncio.sleep(10.0)  # long after: no second call
        if how != "closed":
            if how != "give up":
                await performer.stop()
            await hub.close()
        return ended, calls, client.phase

    return run(main(), hub.clock)


@pytest.mark.parametrize("how", ENDINGS)
def test_the_settled_callback_comes_once_with_the_future_settled(how: str) -> None:
    ended, calls, phase = _ending(how)
    assert phase is ClientPhase.DONE
    assert len(calls) == 1
    done, after_a_done_callback = calls[0]
    assert done
    if how != "future cancel":  # settled by the client: in the same call, before
        assert not after_a_done_callback  # the loop ran a done callback of the future
    expected = {
        "finish": lambda e: e.success,
        "give up": lambda e: e.gave_up and not e.success,
        "client cancel": lambda e: e.cancelled,
        "future cancel": lambda e: e == "cancelled",
        "confirm raises": lambda e: "confirm refused" in e,
        "closed": lambda e: "transport closed" in e,
    }[how]
    assert expected(ended), ended


def test_call_soon_schedules_the_first_step() -> None:
    hub = Hub(InProcessTransport(), VirtualClock())

    async def main() -> tuple[list[Any], bool, Any]:
        await hub.start()
        performer = SimulatedPerformer(
            PerformerContext(hub, hub.clock), "p", {"move": []}, durations={"move": 1.0}
        )
        await performer.start()
        asked: list[Any] = []
        loop = asyncio.get_running_loop()

        def later(callback: Any, *args: Any) -> None:
            asked.append((callback, args))
            loop.call_soon(callback, *args)

        client = ActionClient(hub, "move", ["r1"], request_id="c")
        future = client.start(soon=True, call_soon=later)
        nothing_yet = client.requests_sent == 0
        outcome = await future
        await performer.stop()
        await hub.close()
        return (
            [(cb.__func__.__name__, args == (future,)) for cb, args in asked],
            nothing_yet,
            outcome,
        )

    asked, nothing_yet, outcome = run(main(), hub.clock)
    assert asked == [("_begin_soon", True)]
    assert nothing_yet and outcome.success
