"""The hub-wide table of auction clients (:mod:`plansys_bridge.hub.client_table`)
against one subscription per client (the general path: what every client had before).

With the table the hub must deliver the same messages at the same instants to the
same parties in the same order (clients, and recorders subscribed before, between and
after them), and every action must end the same way. Request ids may be unique, shared
by every client, or empty (then the action text routes, as ``client_keys`` did).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.hub.routing import TopicRouter, client_keys
from plansys_bridge.hub.transport import InProcessTransport, Subscription
from tests.hub.test_hub_auction_properties import SCENARIOS, make_performers

Log = list[tuple[float, str, str]]


class _Observed(ActionClient):
    """A client telling ``heard(robot, msg)`` of each message delivered to it."""

    heard: Callable[[str, object], None]

    def _on_action_msg(self, msg: object) -> None:
        self.heard(self.arguments[0], msg)
        super()._on_action_msg(msg)


class _PerClient(dict[str, Any]):
    """A table's ``by_request`` that stores nobody: each client that joins gets its
    own keyed subscription instead (``client_keys``, as ``Hub.subscribe`` made it),
    closed when it leaves. Empty, so the router never delivers through the table."""

    def __init__(self, router: TopicRouter) -> None:
        super().__init__()
        self.router = router
        self.subs: dict[str, dict[Any, Subscription]] = {}

    def _held(self, rid: str) -> Any:
        clients = list(self.subs[rid])
        return clients[0] if len(clients) == 1 else clients

    def setdefault(self, rid: str, client: Any = None) -> Any:
        if self.subs.get(rid):
            return self._held(rid)
        self[rid] = client
        return client

    def pop(self, rid: str, default: Any = None) -> Any:  # type: ignore[override]
        if not self.subs.get(rid):
            return default
        held = self._held(rid)
        if held.__class__ is not list:
            self.subs.pop(rid)[held].close()
        return held

    def __setitem__(self, rid: str, value: Any) -> None:
        new = value if value.__class__ is list else [value]
        current = self.subs.setdefault(rid, {})
        for client in [c for c in current if c not in new]:
            current.pop(client).close()
        for client in new:
            if client not in current:
                keys = client_keys(rid, client.action, client.arguments)
                current[client] = self.router.add(client._on_action_msg, keys)


def _simulate(
    performers: list[dict[str, Any]],
    actions: list[tuple[str, float, float | None]],
    policy: AuctionPolicy,
    seed: int,
    ids: str,
    recorders: list[float],
) -> tuple[Log, list[tuple[ActionOutcome, float]]]:
    hub = Hub(InProcessTransport(), VirtualClock())
    perfs = make_performers(hub, performers, seed)
    log: Log = []

    def note(who: str, msg: object) -> None:
        if isinstance(msg, ActionExecution):
            log.append((round(asyncio.get_running_loop().time(), 9), who, repr(msg)))

    async def recorder(i: int, at: float) -> None:
        await asyncio.sleep(at)
        hub.subscribe(Topics.ACTIONS_HUB, lambda m: note(f"recorder {i}", m))

    async def one(
        i: int, robot: str, delay: float, cancel_after: float | None
    ) -> tuple[ActionOutcome, float]:
        loop = asyncio.get_running_loop()
        await asyncio.sleep(delay)
        rid = {"unique": f"a{i}", "shared": "a", "empty": ""}[ids]
        client = _Observed(hub, "move", [robot, "a", "b"], request_id=rid, policy=policy)
        client.heard = lambda robot, msg: note(f"client {robot}", msg)
        if cancel_after is not None:
            loop.call_later(cancel_after, client.cancel)
        outcome = await client.run()
        return outcome, loop.time()

    async def main() -> list[tuple[ActionOutcome, float]]:
        await hub.start()
        for p in perfs:
            await p.start()
        watchers = [asyncio.ensure_future(recorder(i, at)) for i, at in enumerate(recorders)]
        outcomes = await asyncio.wait_for(
            asyncio.gather(*(one(i, *a) for i, a in enumerate(actions))), timeout=10_000
        )
        await asyncio.gather(*watchers)
        await asyncio.sleep(policy.give_up_after + 20.0)  # anything still coming would show
        for p in perfs:
            await p.stop()
        await hub.close()
        return list(outcomes)

    return log, run(main(), hub.clock)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    **SCENARIOS,
    ids=st.sampled_from(["unique", "unique", "shared", "empty"]),
    recorders=st.lists(st.sampled_from([0.0, 0.5, 1.0, 2.0, 3.5]), max_size=3),
)
def test_one_table_per_hub_delivers_as_one_subscription_per_client(
    performers: list[dict[str, Any]],
    actions: list[tuple[str, float, float | None]],
    policy: AuctionPolicy,
    seed: int,
    ids: str,
    recorders: list[float],
) -> None:
    table = _simulate(performers, actions, policy, seed, ids, recorders)
    with pytest.MonkeyPatch.context() as patch:
        made = TopicRouter.__init__

        def per_client(router: TopicRouter, topic: str) -> None:
            made(router, topic)
            router.clients.by_request = _PerClient(router)

        patch.setattr(TopicRouter, "__init__", per_client)
        own = _simulate(performers, actions, policy, seed, ids, recorders)
    assert table[0] == own[0]
    assert table[1] == own[1]


def test_a_client_in_the_table_is_delivered_to_in_its_place_among_recorders() -> None:
    """Subscribed between two recorders, the client hears its RESPONSE between them,
    and leaves the table when it ends."""
    hub = Hub(InProcessTransport(), VirtualClock())
    heard: list[str] = []

    def on(name: str, msg: object) -> None:
        if getattr(msg, "type", None) is ExecutionType.RESPONSE:
            heard.append(name)

    def recorder(name: str) -> None:
        hub.subscribe(Topics.ACTIONS_HUB, lambda msg: on(name, msg))

    async def main() -> tuple[Any, int]:
        await hub.start()
        recorder("before")
        client = _Observed(hub, "move", ["r1"], request_id="q")
        client.heard = lambda _robot, msg: on("client", msg)
        future = client.start()
        recorder("after")
        hub.publish(
            Topics.ACTIONS_HUB,
            ActionExecution(ExecutionType.RESPONSE, "p", "move", ("r1",), request_id="q"),
        )
        await asyncio.sleep(0.1)
        assert hub.clients.by_request == {"q": client}
        client.cancel()
        outcome = await future
        left = len(hub.clients.by_request)
        await hub.close()
        return outcome, left

    outcome, left = run(main(), hub.clock)
    assert heard == ["before", "client", "after"]
    assert outcome.cancelled and left == 0
