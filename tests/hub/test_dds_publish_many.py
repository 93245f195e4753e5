"""DdsTransport.publish_many is publish one message at a time, in one call; and what
the reader thread accepts without asking the check is what the check accepts."""

from __future__ import annotations

import asyncio
import itertools
import math
import random

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from test_dds_transport import until, with_pair

from plansys_bridge.errors import HubError
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds import DdsTransport
from plansys_bridge.hub.dds_checks import check_sample
from plansys_bridge.hub.dds_codec import ROUTES

pytestmark = pytest.mark.timeout(120)

HUB = hm.Topics.ACTIONS_HUB
STATUS = hm.Topics.PERFORMERS_STATUS
LOCAL_ONLY = "no_dds_type"
"""A topic without a DDS type: delivered inside the publishing process only."""


def _message(topic: str, run: int, i: int) -> object:
    if topic == STATUS:
        return hm.ActionPerformerStatus(float(i), hm.PerformerState.READY, "move", (), f"n{i}")
    kind = hm.ExecutionType.REJECT if i % 3 else hm.ExecutionType.RESPONSE
    return hm.action_execution(
        kind, f"n{i}", "move", ("r", "a"), bid=float(i), request_id=f"run{run}"
    )


def _wants(msg: object) -> bool:
    """The local subscriber wants some messages only, as a hub's router would."""
    return int(getattr(msg, "node_id", "n0")[1:]) % 2 == 0


Steps = list[tuple[str, str, int]]


async def _run(a: DdsTransport, b: DdsTransport, run: int, steps: Steps, batched: bool) -> tuple:
    local: list[tuple[str, object]] = []
    remote: dict[str, list[object]] = {HUB: [], STATUS: []}
    subs = [
        a.subscribe_wanting(t, lambda m, t=t: local.append((t, m)), _wants)  # type: ignore[misc]
        for t in (HUB, STATUS)
    ]
    subs.append(a.subscribe(LOCAL_ONLY, lambda m: local.append((LOCAL_ONLY, m))))
    subs += [b.subscribe(t, remote[t].append) for t in (HUB, STATUS)]
    published = a.published
    counter = itertools.count()
    for kind, topic, n in steps:
        if kind == "yield":
            await asyncio.sleep(0)
            continue
        msgs = [_message(topic, run, next(counter)) for _ in range(n if kind == "many" else 1)]
        if batched and kind == "many":
            a.publish_many(topic, msgs)
        else:
            for m in msgs:
                a.publish(topic, m)
    sent = {
        t: sum(n if k == "many" else 1 for k, topic, n in steps if topic == t and k != "yield")
        for t in (HUB, STATUS)
    }
    await until(lambda: all(len(remote[t]) >= sent[t] for t in (HUB, STATUS)))
    await asyncio.sleep(0.05)  # nothing more arrives
    for sub in subs:
        sub.close()
    return local, remote, a.published - published


def test_publish_many_delivers_as_publish_one_by_one_locally_and_remotely() -> None:
    rng = random.Random(7)
    cases: list[Steps] = [
        [
            (
                rng.choice(["one", "many", "many", "yield"]),
                rng.choice([HUB, HUB, STATUS, LOCAL_ONLY]),
                rng.randint(0, 6),
            )
            for _ in range(rng.randint(0, 10))
        ]
        for _ in range(12)
    ]
    cases.append([("many", HUB, 200)])  # an auction's REJECTs

    async def body(a: DdsTransport, b: DdsTransport) -> None:
        for run, steps in enumerate(cases):
            one_by_one = await _run(a, b, 2 * run, steps, batched=False)
            batched = await _run(a, b, 2 * run + 1, steps, batched=True)
            # the same messages but for the run they were sent in
            assert repr(batched).replace(f"run{2 * run + 1}'", f"run{2 * run}'") == repr(
                one_by_one
            ), steps

    with_pair(body)


def test_a_message_publish_refuses_stops_publish_many_where_publish_would() -> None:
    good = [_message(HUB, 0, i) for i in range(4)]
    bad = hm.Knowledge(goal="(and)")

    async def body(a: DdsTransport, b: DdsTransport) -> tuple[list[object], list[object], str]:
        local: list[object] = []
        remote: list[object] = []
        a.subscribe(HUB, local.append)
        b.subscribe(HUB, remote.append)
        with pytest.raises(HubError) as one:
            a.publish(HUB, bad)
        with pytest.raises(HubError) as many:
            a.publish_many(HUB, [*good[:2], bad, *good[2:]])
        assert str(many.value) == str(one.value)
        await until(lambda: len(remote) >= 2 and len(local) >= 2)
        await asyncio.sleep(0.05)
        return local, remote, str(many.value)

    local, remote, error = with_pair(body)
    assert local == remote == good[:2]
    assert "cannot publish Knowledge on 'actions_hub' over DDS" in error


BIDS = [None, 0.0, -0.0, 1.5, 1e308, -1e-300, -1.0, math.inf, -math.inf, math.nan]
COMPLETIONS = [0.0, -0.0, 0.5, 1.0, 1.0000001, -1e-9, 2.0, math.inf, math.nan]


def test_the_reader_accepts_exactly_what_check_sample_accepts() -> None:
    route = ROUTES[HUB]
    read = route.project.read  # type: ignore[union-attr]
    write = route.to_bytes[1]
    assert write is not None
    sent = [
        hm.action_execution(
            hm.ExecutionType.RESPONSE, f"n{i}", "move", ("r",), completion=c, bid=bid
        )
        for i, (bid, c) in enumerate(itertools.product(BIDS, COMPLETIONS))
    ]

    def passes(msg: object) -> bool:
        try:
            return check_sample(HUB, read(write(msg))) is None
        except ValueError:  # not a finite number: the reader refuses it
            return False

    expected = [m.node_id for m in sent if passes(m)]

    async def body(a: DdsTransport, b: DdsTransport) -> tuple[list[str], int]:
        got: list[str] = []
        b.subscribe(HUB, lambda m: got.append(m.node_id))  # type: ignore[attr-defined]
        a.publish_many(HUB, sent)
        end = hm.action_execution(hm.ExecutionType.FINISH, "end", "move", ())
        a.publish(HUB, end)
        await until(lambda: "end" in got)
        return got[:-1], b.dropped

    got, dropped = with_pair(body)
    assert got == expected
    assert 0 < dropped == len(sent) - len(expected)


def test_the_batch_filter_says_what_wanted_says_of_each_message() -> None:
    from plansys_bridge.hub.local_interest import LocalInterest

    class Sub:
        closed = False

        def close(self) -> None:
            self.closed = True

    msgs = [_message(HUB, 0, i) for i in range(9)]
    interest = LocalInterest()

    def agree() -> None:
        wants = interest.wants(HUB)
        assert [wants is None or wants(m) for m in msgs] == [interest.wanted(HUB, m) for m in msgs]

    agree()  # nobody subscribed
    first = interest.track(HUB, Sub(), _wants)
    agree()
    second = interest.track(HUB, Sub(), lambda m: m.node_id.endswith("3"))  # type: ignore[attr-defined]
    agree()
    assert interest.wants(HUB)(msgs[3]) and not interest.wants(HUB)(msgs[5])  # type: ignore[misc]
    everything = interest.track(HUB, Sub(), None)
    agree()
    assert interest.wants(HUB) is None
    for sub in (everything, first, second):
        sub.close()
        agree()


def test_a_dds_subscription_takes_batches_once_redirected() -> None:
    """A hub's router rewires its DDS subscription as it would an in-process one: a
    batch published here, and a batch taken from DDS, reach it in one call each."""
    from plansys_bridge.hub.transport import redirect

    msgs = [_message(HUB, 0, i) for i in range(6)]

    async def body(a: DdsTransport, b: DdsTransport) -> tuple[list[list[object]], int]:
        calls: list[list[object]] = []
        sub_a = a.subscribe_wanting(HUB, lambda m: calls.append([m]), _wants)
        sub_b = b.subscribe_wanting(HUB, lambda m: calls.append([m]), None)
        for sub in (sub_a, sub_b):
            assert redirect(sub, lambda m: calls.append([m]), lambda ms: calls.append(list(ms)))
        a.publish_many(HUB, msgs)
        await until(lambda: sum(map(len, calls)) >= 3 + len(msgs))
        await asyncio.sleep(0.05)
        sub_a.close()
        a.publish_many(HUB, msgs)  # nobody here any more
        await until(lambda: sum(map(len, calls)) >= 3 + 2 * len(msgs))
        await asyncio.sleep(0.05)
        return calls, sum(map(len, calls))

    calls, total = with_pair(body)
    wanted = [m for m in msgs if _wants(m)]
    assert calls[0] == wanted  # at home: the wanted ones, one call
    assert [m for batch in calls[1:] for m in batch] == msgs + msgs  # remote: all, in order
    assert total == len(wanted) + 2 * len(msgs)
