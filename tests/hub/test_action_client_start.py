"""ActionClient.start: the outcome future without a task, against run().

``run()`` in a task is the general path; ``start(soon=True)`` must send the same messages
at the same instants and in the same order, and cancelling its future must do what
cancelling run()'s task did (REJECTs to pending bidders, a CANCEL to the performer).
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.errors import HubError
from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy, ClientPhase
from plansys_bridge.hub.auction_policy import action_outcome
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer
from tests.conftest import HubRecorder

Body = Callable[[Hub], Awaitable[Any]]


def _scenario(body: Body, performers: list[tuple[str, float, float | None]]) -> Any:
    """Run ``body(hub)`` on a fresh virtual hub with simulated ``move`` performers
    (name, duration, feedback period); returns what body returned."""
    hub = Hub(InProcessTransport(), VirtualClock())

    async def main() -> Any:
        await hub.start()
        started = []
        for name, duration, feedback in performers:
            p = SimulatedPerformer(
                PerformerContext(hub, hub.clock),
                name,
                {"move": []},
                durations={"move": duration},
                feedback_period=feedback,
            )
            await p.start()
            started.append(p)
        try:
            return await body(hub)
        finally:
            for p in started:
                await p.stop()
            await hub.close()

    return run(main(), hub.clock)


def _drive(
    via: str, policy: AuctionPolicy, cancel_at: float | None, how: str, fail_on: str = ""
) -> Body:
    """A body that runs one client through ``via`` ("task": run() in a task, "soon":
    start(soon=True), "start": start()), stopping it at ``cancel_at`` by ``how``
    ("future": cancelling the task or future, "client": ``client.cancel()``).
    The last item returned is what the future's cancel() said (None when not used)."""

    async def body(hub: Hub) -> Any:
        rec = HubRecorder(hub)
        seen: list[Any] = []

        def on_confirm(node: str) -> None:
            seen.append(("confirm", node))
            if fail_on == "confirm":
                raise RuntimeError("confirm refused")

        def on_feedback(completion: float, status: str) -> None:
            seen.append(("feedback", completion, status))
            if fail_on == "feedback":
                raise RuntimeError("feedback refused")

        client = ActionClient(hub, "move", ["r1"], request_id="x", policy=policy)
        waiter: asyncio.Future[Any]
        took: bool | None = None
        if via == "task":
            waiter = asyncio.ensure_future(client.run(on_feedback, confirm_cb=on_confirm))
        elif via == "soon":
            waiter = client.start(on_feedback, confirm_cb=on_confirm, soon=True)
        else:
            waiter = client.start(on_feedback, confirm_cb=on_confirm)
        if cancel_at is not None:
            await asyncio.sleep(cancel_at)
            if how == "future":
                took = waiter.cancel()
            else:
                client.cancel()
        try:
            ended: Any = await waiter
        except asyncio.CancelledError:
            ended = "cancelled"
        except RuntimeError as exc:
            ended = repr(exc)
        await asyncio.sleep(40.0)  # long after: nothing more may come
        rec.close()
        timeline = rec.timeline(request_ids=True)
        return ended, timeline, seen, client.phase, client.performer, took

    return body


def _assert_agree(general: Any, fast: Any) -> None:
    """Full equality, except for the tie described in the module docstring: there the
    task's cancel() took and the done future's did not, and only the ending differs."""
    if general[5] is True and fast[5] is False:
        assert fast[1:5] == general[1:5]
        assert general[0] == "cancelled" and fast[0] != "cancelled"
    else:
        assert fast == general


PERFORMERS = [("p1", 3.0, 1.0), ("p2", 2.0, None)]


def test_start_soon_and_run_in_a_task_agree_on_a_plain_run() -> None:
    policy = AuctionPolicy()
    general = _scenario(_drive("task", policy, None, ""), PERFORMERS)
    fast = _scenario(_drive("soon", policy, None, ""), PERFORMERS)
    assert fast == general
    outcome, timeline, seen, phase, _, _ = fast
    assert outcome.success and phase is ClientPhase.DONE
    kinds = [kind for _, kind, _, _ in timeline]
    assert kinds[:3] == ["REQUEST", "RESPONSE", "RESPONSE"] and kinds[-1] == "FINISH"
    assert ("CONFIRM", outcome.performer) in [(kind, node) for _, kind, node, _ in timeline]
    assert seen[0] == ("confirm", outcome.performer)


def test_cancelling_the_future_cancels_the_performer_as_cancelling_the_task_did() -> None:
    policy = AuctionPolicy()
    general = _scenario(_drive("task", policy, 1.5, "future"), PERFORMERS)
    fast = _scenario(_drive("soon", policy, 1.5, "future"), PERFORMERS)
    assert fast == general
    ended, timeline, _, phase, performer, took = fast
    assert ended == "cancelled" and phase is ClientPhase.DONE and took is True
    assert timeline[-1] == (1.5, "CANCEL", performer, "x")
    assert not any(kind == "FINISH" for _, kind, _, _ in timeline)


def test_cancelling_the_future_in_a_best_bid_auction_rejects_every_bidder() -> None:
    policy = AuctionPolicy(selection="best_bid", bid_window=1.0)
    general = _scenario(_drive("task", policy, 0.5, "future"), PERFORMERS)
    fast = _scenario(_drive("start", policy, 0.5, "future"), PERFORMERS)
    assert fast == general
    _, timeline, _, _, performer, _ = fast
    assert performer == ""
    assert sorted(node for _, kind, node, _ in timeline if kind == "REJECT") == ["p1", "p2"]


@pytest.mark.parametrize("fail_on", ["confirm", "feedback"])
def test_a_failing_callback_fails_the_future_and_cancels_the_performer(fail_on: str) -> None:
    policy = AuctionPolicy()
    general = _scenario(_drive("task", policy, None, "", fail_on), PERFORMERS)
    fast = _scenario(_drive("soon", policy, None, "", fail_on), PERFORMERS)
    assert fast == general
    ended, timeline, _, _, performer, _ = fast
    assert ended == f"RuntimeError('{fail_on} refused')"
    assert ("CANCEL", performer) in [(kind, node) for _, kind, node, _ in timeline]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    selection=st.sampled_from(["first", "best_bid"]),
    bid_window=st.sampled_from([0.0, 0.5, 1.5]),
    liveness=st.sampled_from([0.5, 5.0]),
    cancel_at=st.one_of(st.none(), st.sampled_from([0.0, 0.25, 1.0, 2.0, 2.5, 4.0])),
    how=st.sampled_from(["future", "client"]),
    fail_on=st.sampled_from(["", "", "confirm", "feedback"]),
    performers=st.lists(
        st.tuples(
            st.sampled_from(["a", "b", "c"]),
            st.sampled_from([0.0, 1.0, 3.0]),
            st.sampled_from([None, 0.5, 1.0]),
        ),
        max_size=3,
        unique_by=lambda p: p[0],
    ),
)
def test_start_soon_agrees_with_run_in_a_task(
    selection: str,
    bid_window: float,
    liveness: float,
    cancel_at: float | None,
    how: str,
    fail_on: str,
    performers: list[tuple[str, float, float | None]],
) -> None:
    policy = AuctionPolicy(
        selection=selection,  # type: ignore[arg-type]
        bid_window=bid_window,
        liveness_timeout=liveness,
        retry_period=0.5,
        give_up_after=3.0,
    )
    general = _scenario(_drive("task", policy, cancel_at, how, fail_on), performers)
    fast = _scenario(_drive("soon", policy, cancel_at, how, fail_on), performers)
    _assert_agree(general, fast)


def test_start_soon_sends_nothing_before_the_loop_runs_its_callback() -> None:
    async def body(hub: Hub) -> Any:
        rec = HubRecorder(hub)
        client = ActionClient(hub, "move", ["r1"], request_id="s")
        future = client.start(soon=True)
        assert client.phase is ClientPhase.NEW and client.requests_sent == 0
        outcome = await future
        return outcome, rec.kinds()

    outcome, kinds = _scenario(body, [("p", 0.0, None)])
    assert outcome.success and kinds[:3] == [("REQUEST", ""), ("RESPONSE", "p"), ("CONFIRM", "p")]


@pytest.mark.parametrize("how", ["future", "client"])
def test_stopped_before_its_first_request_a_client_sends_nothing(how: str) -> None:
    """As a task cancelled (or a client cancelled) before the task's first step."""

    async def body(hub: Hub) -> Any:
        rec = HubRecorder(hub)
        client = ActionClient(hub, "move", ["r1"], request_id="n")
        future = client.start(soon=True)
        if how == "future":
            future.cancel()
        else:
            client.cancel()
        try:
            ended: Any = await future
        except asyncio.CancelledError:
            ended = "cancelled"
        await asyncio.sleep(5.0)
        return ended, rec.kinds(), client.phase

    ended, kinds, phase = _scenario(body, [("p", 1.0, None)])
    assert kinds == [] and phase is ClientPhase.DONE
    if how == "future":
        assert ended == "cancelled"
    else:
        assert ended.cancelled and not ended.success and ended.performer == ""


@pytest.mark.parametrize("first", ["start", "start soon", "run"])
def test_a_client_starts_once(first: str) -> None:
    async def body(hub: Hub) -> Any:
        client = ActionClient(hub, "move", ["r1"], request_id="o")
        if first == "run":
            await client.run()
        else:
            await client.start(soon=first == "start soon")
        for soon in (False, True):
            with pytest.raises(HubError, match=r"start\(\) may be called only once"):
                client.start(soon=soon)
        with pytest.raises(HubError, match=r"run\(\) may be called only once"):
            await client.run()

    _scenario(body, [("p", 0.0, None)])


def test_a_closed_transport_fails_start_at_once_and_start_soon_through_its_future() -> None:
    hub = Hub(InProcessTransport(), VirtualClock())

    async def main() -> Any:
        await hub.start()
        clients = [ActionClient(hub, "move", ["r1"], request_id=str(i)) for i in range(3)]
        soon = clients[0].start(soon=True)
        task = asyncio.ensure_future(clients[1].run())
        await hub.close()
        with pytest.raises(HubError, match="transport closed") as direct:
            clients[2].start()
        errors = [(await asyncio.gather(f, return_exceptions=True))[0] for f in (soon, task)]
        return direct.value, errors, [c.phase for c in clients]

    direct, errors, phases = run(main(), hub.clock)
    assert isinstance(direct, HubError) and repr(errors[0]) == repr(errors[1])
    assert isinstance(errors[0], HubError) and "transport closed" in str(errors[0])
    assert phases == [ClientPhase.DONE] * 3


@given(
    success=st.booleans(),
    status=st.text(max_size=20),
    completion=st.floats(allow_nan=False),
    performer=st.text(max_size=10),
    reauctioned=st.integers(0, 5),
    cancelled=st.booleans(),
    gave_up=st.booleans(),
    lost=st.lists(st.text(max_size=5), max_size=3).map(tuple),
)
def test_action_outcome_equals_the_dataclass_constructors_outcome(
    success: bool,
    status: str,
    completion: float,
    performer: str,
    reauctioned: int,
    cancelled: bool,
    gave_up: bool,
    lost: tuple[str, ...],
) -> None:
    args = (success, status, completion, performer, reauctioned, cancelled, gave_up, lost)
    fast = action_outcome(*args)
    general = ActionOutcome(*args)
    assert fast == general and hash(fast) == hash(general) and repr(fast) == repr(general)
    assert list(vars(fast)) == list(vars(general))  # same fields, same order
    with pytest.raises(AttributeError):
        fast.status = "changed"  # type: ignore[misc]  # still frozen
