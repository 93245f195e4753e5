"""The in-process transport: ordered, asynchronous, closable delivery."""

from __future__ import annotations

import asyncio
import threading

import pytest

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.errors import HubError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport, Subscription, Transport, redirect


def test_in_process_transport_is_a_transport() -> None:
    assert isinstance(InProcessTransport(), Transport)


def test_delivery_keeps_publish_order_across_topics_and_is_asynchronous() -> None:
    async def main() -> tuple[list[tuple[str, object]], list[tuple[str, object]]]:
        transport = InProcessTransport()
        await transport.start()
        got: list[tuple[str, object]] = []
        transport.subscribe("a", lambda m: got.append(("a", m)))
        transport.subscribe("b", lambda m: got.append(("b", m)))
        transport.publish("a", 1)
        transport.publish("b", 2)
        transport.publish("a", 3)
        transport.publish("nobody", 4)  # no subscriber: fine
        during = list(got)
        await asyncio.sleep(0)
        await transport.close()
        return during, got

    during, got = run(main(), VirtualClock())
    assert during == []  # never delivered inside publish()
    assert got == [("a", 1), ("b", 2), ("a", 3)]


def test_every_subscriber_gets_each_message_and_close_stops_queued_ones() -> None:
    async def main() -> tuple[list[object], list[object]]:
        hub = Hub(InProcessTransport(), VirtualClock())
        await hub.start()
        first: list[object] = []
        second: list[object] = []
        sub1: Subscription = hub.subscribe("t", first.append)
        hub.subscribe("t", second.append)
        hub.publish("t", "x")
        await asyncio.sleep(0)
        hub.publish("t", "y")
        sub1.close()  # "y" is queued but must not reach a closed subscription
        sub1.close()  # idempotent
        await asyncio.sleep(0)
        await hub.close()
        return first, second

    assert run(main(), VirtualClock()) == (["x"], ["x", "y"])


def test_a_subscription_made_after_publish_does_not_see_the_message() -> None:
    async def main() -> list[object]:
        transport = InProcessTransport()
        await transport.start()
        got: list[object] = []
        transport.subscribe("t", lambda m: None)
        transport.publish("t", "early")
        transport.subscribe("t", got.append)
        transport.publish("t", "late")
        await asyncio.sleep(0)
        await transport.close()
        return got

    assert run(main(), VirtualClock()) == ["late"]


@pytest.mark.allow_asyncio_errors
def test_a_failing_subscriber_does_not_stop_the_others() -> None:
    errors: list[str] = []

    async def main() -> list[object]:
        loop = asyncio.get_running_loop()
        loop.set_exception_handler(lambda _loop, ctx: errors.append(ctx["message"]))
        transport = InProcessTransport()
        await transport.start()
        got: list[object] = []

        def boom(_msg: object) -> None:
            raise ValueError("bad subscriber")

        transport.subscribe("t", boom)
        transport.subscribe("t", got.append)
        transport.publish("t", 1)
        await asyncio.sleep(0)
        await transport.close()
        return got

    assert run(main(), VirtualClock()) == [1]
    assert errors == ["subscriber of 't' raised ValueError: bad subscriber"]


def test_publish_from_another_thread_is_delivered_on_the_loop() -> None:
    async def main() -> tuple[object, bool]:
        transport = InProcessTransport()
        await transport.start()
        loop = asyncio.get_running_loop()
        got: asyncio.Future[tuple[object, bool]] = loop.create_future()
        loop_thread = threading.get_ident()
        transport.subscribe(
            "t", lambda m: got.set_result((m, threading.get_ident() == loop_thread))
        )
        thread = threading.Thread(target=transport.publish, args=("t", "from thread"))
        thread.start()
        result = await got
        await loop.run_in_executor(None, thread.join)
        await transport.close()
        return result

    assert run(main(), VirtualClock()) == ("from thread", True)


def test_closed_transport_refuses_publish_and_subscribe() -> None:
    async def main() -> None:
        transport = InProcessTransport()
        await transport.start()
        await transport.close()
        with pytest.raises(HubError, match="'t'"):
            transport.publish("t", 1)
        with pytest.raises(HubError, match="'t'"):
            transport.subscribe("t", lambda m: None)

    run(main(), VirtualClock())


def test_publishing_before_any_loop_names_the_topic() -> None:
    transport = InProcessTransport()
    transport.subscribe("status", lambda m: None)
    with pytest.raises(HubError, match=r"'status'.*no event loop"):
        transport.publish("status", 1)


def test_a_queued_batch_follows_its_subscription_redirected_or_closed() -> None:
    """A ``publish_many`` batch waits for the drain; if the subscription is redirected
    meanwhile the batch goes where it now points (one by one without ``many``), and
    if it is closed (or the transport is) nothing is delivered."""

    async def main() -> list[tuple[str, object]]:
        transport = InProcessTransport()
        await transport.start()
        got: list[tuple[str, object]] = []
        subs = {t: transport.subscribe(t, lambda m: got.append(("one", m))) for t in "abcd"}
        for t in "abcd":
            assert redirect(
                subs[t], lambda m: got.append(("one", m)), lambda ms: got.append(("first", ms))
            )
        for t in "abcd":
            transport.publish_many(t, [f"{t}1", f"{t}2"])
        redirect(subs["a"], lambda m: got.append(("new one", m)))
        redirect(
            subs["b"], lambda m: got.append(("new one", m)), lambda ms: got.append(("new", ms))
        )
        subs["c"].close()
        await asyncio.sleep(0)
        transport.publish_many("d", ["d3"])
        await transport.close()
        await asyncio.sleep(0)
        return got

    assert run(main(), VirtualClock()) == [
        ("new one", "a1"),
        ("new one", "a2"),
        ("new", ["b1", "b2"]),
        ("first", ["d1", "d2"]),
    ]
