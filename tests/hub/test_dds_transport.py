"""DdsTransport through real Cyclone DDS on loopback: delivery, order, duplicates, errors."""

from __future__ import annotations

import asyncio
import logging
import os
import random
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TypeVar

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.errors import ConfigError, HubError
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds import DdsTransport
from plansys_bridge.hub.dds_config import loopback_config
from plansys_bridge.hub.transport import Transport
from plansys_bridge.interfaces.dds import dds_type

pytestmark = pytest.mark.timeout(60)

R = TypeVar("R")


def random_domain() -> int:
    """A domain id of its own, so parallel test runs never hear each other."""
    return random.SystemRandom().randint(1, 232)


def with_pair(body: Callable[[DdsTransport, DdsTransport], Awaitable[R]]) -> R:
    """Run ``body(a, b)`` with two started, matched transports on one fresh domain."""

    async def main() -> R:
        domain = random_domain()
        a, b = DdsTransport(domain), DdsTransport(domain)
        try:
            await a.start()
            await b.start()
            await a.wait_for_peers(1, timeout=5)
            await b.wait_for_peers(1, timeout=5)
            return await asyncio.wait_for(body(a, b), 10)
        finally:
            await b.close()
            await a.close()

    return asyncio.run(main())


async def until(condition: Callable[[], bool], timeout: float = 5.0) -> None:
    async with asyncio.timeout(timeout):
        while not condition():
            await asyncio.sleep(0.005)


SAMPLES: list[tuple[str, object, object]] = [
    # (topic, published, received): stamps chosen to be exact in nanoseconds.
    (
        hm.Topics.ACTIONS_HUB,
        hm.ActionExecution(
            hm.ExecutionType.RESPONSE, "r1", "move", ("r1", "a"), False, 0.5, "", 3.25, "p:1"
        ),
        None,
    ),
    (
        hm.Topics.ACTION_EXECUTION_INFO,
        hm.ActionExecutionInfo(
            hm.ActionStatus.SUCCEEDED, 1.5, 1790000000.25, "(move r1 a)", "move", ("r1",), 3.75
        ),
        None,
    ),
    (
        hm.Topics.PERFORMERS_STATUS,
        hm.ActionPerformerStatus(2.5, hm.PerformerState.READY, "move", ("r1", ""), "r1"),
        None,
    ),
    (
        hm.Topics.EXECUTING_PLAN,
        hm.ExecutingPlan(hm.Plan((hm.PlanItem(0.0, "(move r1 a b)", 3.5),)), "plan-7"),
        None,
    ),
    (hm.Topics.KNOWLEDGE, hm.Knowledge(("r1",), ("(robot_at r1 a)",), (), "(and)"), None),
    (hm.Topics.DOT_GRAPH, hm.DotGraph("digraph {}", "plan-7"), hm.DotGraph("digraph {}")),
]


def test_dds_transport_is_a_transport() -> None:
    assert isinstance(DdsTransport(random_domain()), Transport)


def test_every_hub_message_crosses_dds_between_participants() -> None:
    async def body(a: DdsTransport, b: DdsTransport) -> list[tuple[str, object]]:
        got: list[tuple[str, object]] = []

        def collect(topic: str) -> Callable[[object], None]:
            return lambda m: got.append((topic, m))

        for topic, _, _ in SAMPLES:
            b.subscribe(topic, collect(topic))
        for topic, msg, _ in SAMPLES:
            a.publish(topic, msg)
        await until(lambda: len(got) >= len(SAMPLES))
        await asyncio.sleep(0.05)  # nothing more (no duplicates) arrives
        return got

    got = with_pair(body)
    expected = [(t, want if want is not None else msg) for t, msg, want in SAMPLES]
    assert sorted(got, key=repr) == sorted(expected, key=repr)


def test_order_per_topic_and_exactly_once_including_own_messages() -> None:
    n = 300

    async def body(a: DdsTransport, b: DdsTransport) -> tuple[list[object], list[object]]:
        remote: list[object] = []
        own: list[object] = []
        b.subscribe(hm.Topics.ACTIONS_HUB, remote.append)
        a.subscribe(hm.Topics.ACTIONS_HUB, own.append)
        loop = asyncio.get_running_loop()
        for i in range(n):
            a.publish(
                hm.Topics.ACTIONS_HUB,
                hm.ActionExecution(hm.ExecutionType.FEEDBACK, "r1", "move", request_id=str(i)),
            )
            if i % 50 == 0:
                await asyncio.sleep(0)  # let the reader thread interleave with publishing
        await until(lambda: len(remote) >= n and len(own) >= n)
        await asyncio.sleep(0.05)
        assert loop is asyncio.get_running_loop()
        return remote, own

    remote, own = with_pair(body)
    ids = [str(i) for i in range(n)]
    assert [m.request_id for m in remote] == ids  # type: ignore[attr-defined]
    assert [m.request_id for m in own] == ids  # type: ignore[attr-defined]


def test_callbacks_run_on_the_loop_thread() -> None:
    async def body(a: DdsTransport, b: DdsTransport) -> bool:
        import threading

        loop_thread = threading.get_ident()
        seen: list[int] = []
        b.subscribe(hm.Topics.KNOWLEDGE, lambda _m: seen.append(threading.get_ident()))
        a.publish(hm.Topics.KNOWLEDGE, hm.Knowledge(goal="(and)"))
        await until(lambda: bool(seen))
        return seen == [loop_thread]

    assert with_pair(body)


def test_plain_messages_of_another_dds_node_arrive_with_default_project_fields() -> None:
    """A PlanSys2 node writes only rt/actions_hub; its messages are not dropped."""

    async def body(a: DdsTransport, b: DdsTransport) -> list[object]:
        got: list[object] = []
        b.subscribe(hm.Topics.ACTIONS_HUB, got.append)
        foreign = DomainParticipant(a.domain_id)
        try:
            topic = Topic(foreign, "rt/actions_hub", dds_type("plansys2_msgs/msg/ActionExecution"))
            writer = DataWriter(foreign, topic)
            async with asyncio.timeout(5):
                while writer.get_publication_matched_status().current_count < 2:
                    await asyncio.sleep(0.01)
            writer.write(
                dds_type("plansys2_msgs/msg/ActionExecution")(
                    type=2, node_id="ros_node", action="move"
                )
            )
            await until(lambda: bool(got))
            await asyncio.sleep(0.05)
        finally:
            foreign.__del__()
        return got

    assert with_pair(body) == [
        hm.ActionExecution(hm.ExecutionType.RESPONSE, "ros_node", "move", bid=None, request_id="")
    ]


def test_topics_without_a_dds_type_stay_in_the_process(caplog: pytest.LogCaptureFixture) -> None:
    async def body(a: DdsTransport, b: DdsTransport) -> tuple[list[object], list[object]]:
        mine: list[object] = []
        theirs: list[object] = []
        a.subscribe("robot/battery", mine.append)
        b.subscribe("robot/battery", theirs.append)
        with caplog.at_level(logging.WARNING, logger="plansys_bridge.hub.dds"):
            a.publish("robot/battery", 0.42)
            a.publish("robot/battery", 0.41)
        await until(lambda: len(mine) == 2)
        await asyncio.sleep(0.05)
        return mine, theirs

    assert with_pair(body) == ([0.42, 0.41], [])
    warnings = [r for r in caplog.records if "no DDS type" in r.getMessage()]
    assert len(warnings) == 1  # once per topic


def test_misuse_is_a_clear_error() -> None:
    async def main() -> None:
        t = DdsTransport(random_domain())
        with pytest.raises(HubError, match="start the DDS transport first"):
            t.publish(hm.Topics.KNOWLEDGE, hm.Knowledge())
        await t.start()
        try:
            with pytest.raises(HubError, match="cannot publish Knowledge on 'actions_hub'"):
                t.publish(hm.Topics.ACTIONS_HUB, hm.Knowledge())
            with pytest.raises(
                HubError, match="0 of 1 peers on rt/actions_hub, rt/plansys_bridge/actions_hub"
            ):
                await t.wait_for_peers(1, timeout=0.1)
        finally:
            await t.close()
        with pytest.raises(HubError, match="transport closed"):
            t.publish(hm.Topics.KNOWLEDGE, hm.Knowledge())
        with pytest.raises(HubError, match="transport closed"):
            t.subscribe(hm.Topics.KNOWLEDGE, print)
        with pytest.raises(HubError, match="closed DDS transport"):
            await t.start()

    asyncio.run(main())
    with pytest.raises(ConfigError, match=r"domain_id must be within 0\.\.232"):
        DdsTransport(300)


def test_the_virtual_clock_is_refused() -> None:
    async def main() -> None:
        t = DdsTransport(random_domain())
        try:
            await t.start()
        finally:
            await t.close()

    with pytest.raises(HubError, match="needs the wall clock"):
        run(main(), VirtualClock())


def test_closed_subscriptions_and_transports_deliver_nothing() -> None:
    async def body(a: DdsTransport, b: DdsTransport) -> list[object]:
        got: list[object] = []
        sub = b.subscribe(hm.Topics.KNOWLEDGE, got.append)
        a.publish(hm.Topics.KNOWLEDGE, hm.Knowledge(goal="1"))
        await until(lambda: len(got) == 1)
        sub.close()
        a.publish(hm.Topics.KNOWLEDGE, hm.Knowledge(goal="2"))
        await asyncio.sleep(0.1)
        return got

    assert with_pair(body) == [hm.Knowledge(goal="1")]


def _udp_sockets_of_this_process() -> list[tuple[str, int]]:
    """``(address, port)`` of every UDP socket this process holds (IPv4), from /proc."""
    inodes = set()
    for fd in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    out = []
    for line in Path("/proc/self/net/udp").read_text().splitlines()[1:]:
        fields = line.split()
        if fields[9] in inodes:
            addr_hex, port_hex = fields[1].split(":")
            octets = bytes.fromhex(addr_hex)[::-1]
            out.append((".".join(str(o) for o in octets), int(port_hex, 16)))
    return out


@pytest.mark.skipif(not Path("/proc/self/net/udp").exists(), reason="needs Linux /proc")
def test_loopback_config_sends_from_loopback_and_opens_no_multicast_port() -> None:
    config = loopback_config(17)
    assert '<NetworkInterface address="127.0.0.1" multicast="false"/>' in config
    assert "<AllowMulticast>false</AllowMulticast>" in config
    assert '<Peer address="127.0.0.1"/>' in config

    async def main() -> list[tuple[str, int]]:
        before = set(_udp_sockets_of_this_process())
        t = DdsTransport(domain)
        await t.start()
        try:
            return [s for s in _udp_sockets_of_this_process() if s not in before]
        finally:
            await t.close()

    domain = random_domain()
    sockets = asyncio.run(main())
    base = 7400 + 250 * domain
    assert sockets
    for address, port in sockets:
        # Cyclone binds its well-known unicast receive ports (base + 10 + 2i, +1) on all
        # addresses; everything it sends goes from a socket bound to 127.0.0.1.
        if address != "127.0.0.1":
            assert address == "0.0.0.0"
            assert base + 10 <= port <= base + 10 + 2 * 20 + 1, (address, port)
    assert any(address == "127.0.0.1" for address, _ in sockets)
    assert all(port not in (base, base + 1) for _, port in sockets)  # no multicast ports


def test_two_transports_share_one_domain_but_not_two_configs() -> None:
    async def main() -> None:
        domain = random_domain()
        a = DdsTransport(domain)
        b = DdsTransport(domain, config=loopback_config(domain, max_participants=5))
        await a.start()
        try:
            with pytest.raises(HubError, match="already open in this process"):
                await b.start()
        finally:
            await b.close()
            await a.close()

    asyncio.run(main())
