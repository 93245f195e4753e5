"""The contract every transport plugin keeps, as tests a transport package inherits.

Subclass :class:`TransportContract` and name your transport as it is registered in
the ``plansys_bridge.transports`` entry-point group::

    class TestMyBus(TransportContract):
        transport = "mybus"
        settings = {"port": 0}          # optional: its mission-file settings

What is checked, on hubs running on the transport: messages published on a topic
reach its subscribers in publish order (and, for a transport between processes, a
second hub built from the same settings); an auction is routed end to end (a
performer answers the REQUEST, is CONFIRMed and FINISHes); garbage (an object no hub
topic carries, a subscriber that raises) is refused at the sender or dropped and
traffic keeps flowing; a closed subscription delivers nothing more.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator, Callable, Coroutine
from typing import Any, ClassVar

import pytest

from plansys_bridge.clock import Clock, WallClock, run
from plansys_bridge.errors import HubError
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.hub.transport_kinds import TRANSPORTS, TransportContext, TransportKind
from plansys_bridge.performers.goal import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer
from plansys_bridge.plugins import validate_settings

__all__ = ["TransportContract"]


class TransportContract:
    """Inherit to run the transport contract; set ``transport`` (and ``settings``)."""

    transport: ClassVar[str] = "inprocess"
    """The name the transport is registered under."""
    settings: ClassVar[dict[str, Any]] = {}
    """Its mission-file settings (the keys of ``transport:`` besides ``kind``)."""
    deliver_within: ClassVar[float] = 10.0
    """Seconds a message may take to arrive (discovery included)."""

    def make_clock(self) -> Clock:
        return WallClock()

    def kind(self) -> TransportKind:
        cls = TRANSPORTS.load(self.transport)
        return cls(validate_settings(cls.Settings, dict(self.settings), key="transport"))

    @contextlib.asynccontextmanager
    async def hub(self, clock: Clock, role: str) -> AsyncIterator[Hub]:
        hub = Hub(self.kind().create(TransportContext(node_name=f"contract_{role}")), clock)
        await hub.start()
        try:
            yield hub
        finally:
            await hub.close()

    def _run(self, body: Callable[[Clock], Coroutine[Any, Any, None]]) -> None:
        clock = self.make_clock()
        run(body(clock), clock)

    async def _until(self, done: Callable[[], bool]) -> bool:
        loop = asyncio.get_running_loop()
        end = loop.time() + self.deliver_within
        while not done():
            if loop.time() >= end:
                return False
            await asyncio.sleep(0.01)
        return True

    # ------------------------------------------------------------ the contract

    def test_contract_registered_with_its_settings(self) -> None:
        kind = self.kind()
        assert isinstance(kind, TransportKind)
        assert kind.settings is not None

    def test_contract_delivers_in_publish_order(self) -> None:
        async def body(clock: Clock) -> None:
            async with contextlib.AsyncExitStack() as stack:
                first = await stack.enter_async_context(self.hub(clock, "a"))
                hubs = [first]
                if self.kind().distributed:
                    hubs.append(await stack.enter_async_context(self.hub(clock, "b")))
                seen: list[list[str]] = [[] for _ in hubs]
                for hub, into in zip(hubs, seen, strict=True):
                    hub.subscribe(Topics.ACTIONS_HUB, _request_ids(into))
                probe = _request("probe")
                # a transport between processes first discovers its peers
                end = asyncio.get_running_loop().time() + self.deliver_within
                while not all("probe" in s for s in seen):
                    if asyncio.get_running_loop().time() > end:
                        raise AssertionError(f"nothing delivered in {self.deliver_within} s")
                    first.publish(Topics.ACTIONS_HUB, probe)
                    await asyncio.sleep(0.2)
                sent = [f"m{i}" for i in range(50)]
                for request_id in sent:
                    first.publish(Topics.ACTIONS_HUB, _request(request_id))
                assert await self._until(lambda: all(s[-1:] == ["m49"] for s in seen)), seen
                for into in seen:
                    assert [r for r in into if r.startswith("m")] == sent

        self._run(body)

    def test_contract_routes_an_auction(self) -> None:
        async def body(clock: Clock) -> None:
            async with contextlib.AsyncExitStack() as stack:
                executor = await stack.enter_async_context(self.hub(clock, "executor"))
                side = executor
                if self.kind().distributed:
                    side = await stack.enter_async_context(self.hub(clock, "performers"))
                performer = SimulatedPerformer(
                    PerformerContext(side, clock),
                    "contract_robot",
                    {"move": ["r1"]},
                    durations={"move": 0.2},
                    heartbeat_period=0.2,
                )
                await performer.start()
                stack.push_async_callback(performer.stop)
                outcome = await asyncio.wait_for(
                    ActionClient(executor, "move", ("r1", "a", "b")).run(),
                    self.deliver_within + 5.0,
                )
                assert outcome.success, outcome
                assert outcome.performer == "contract_robot"

        self._run(body)

    @pytest.mark.allow_asyncio_errors  # the failing subscriber is logged, as it should be
    def test_contract_survives_garbage(self) -> None:
        async def body(clock: Clock) -> None:
            async with self.hub(clock, "a") as hub:
                seen: list[str] = []

                def explode(msg: object) -> None:
                    raise RuntimeError("a subscriber that fails")

                hub.subscribe(Topics.ACTIONS_HUB, explode)
                hub.subscribe(Topics.ACTIONS_HUB, _request_ids(seen))
                with contextlib.suppress(HubError):
                    hub.publish(Topics.ACTIONS_HUB, object())
                with contextlib.suppress(HubError):
                    hub.publish(Topics.ACTIONS_HUB, ActionExecution(ExecutionType.REQUEST, "", "x"))
                hub.publish(Topics.ACTIONS_HUB, _request("after"))
                assert await self._until(lambda: "after" in seen), seen

        self._run(body)

    def test_contract_closed_subscription_delivers_nothing(self) -> None:
        async def body(clock: Clock) -> None:
            async with self.hub(clock, "a") as hub:
                seen: list[str] = []
                sub = hub.subscribe(Topics.ACTIONS_HUB, _request_ids(seen))
                hub.publish(Topics.ACTIONS_HUB, _request("before"))
                assert await self._until(lambda: "before" in seen)
                sub.close()
                hub.publish(Topics.ACTIONS_HUB, _request("after"))
                await asyncio.sleep(0.3)
                assert "after" not in seen, seen

        self._run(body)


def _request(request_id: str) -> ActionExecution:
    return ActionExecution(
        ExecutionType.REQUEST, "", "move", ("r1", "a", "b"), request_id=request_id
    )


def _request_ids(into: list[str]) -> Callable[[object], None]:
    def on_msg(msg: object) -> None:
        if isinstance(msg, ActionExecution) and msg.type == ExecutionType.REQUEST:
            into.append(msg.request_id)

    return on_msg
