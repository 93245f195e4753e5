"""What only informs (the plan on ``executing_plan``, its DOT graph, the execution
info) is made only for an audience: with nobody subscribed nothing of it is
published, the mission runs the same, and a subscriber that comes while the plan runs
gets from then on exactly what one there from the start got (the DOT graph made late
shows every step in the state it is in)."""

from __future__ import annotations

import asyncio
import dataclasses
import re

import pytest
from execution_helpers import run_scenario

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import DotGraph, Topics
from plansys_bridge.hub.transport import InProcessTransport, Subscription
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer
from tests.execution.test_execution_rates import PERFORMERS, PLAN, _execute, _world

INFORMING = (Topics.EXECUTING_PLAN, Topics.DOT_GRAPH, Topics.ACTION_EXECUTION_INFO)
OPTIONS = ExecutorOptions(dot_period=0.5)


def _from_the_start() -> list[tuple[float, str, object]]:
    domain, k = _world()
    found = run_scenario(domain, k, _execute(PLAN), PERFORMERS, options=OPTIONS, topics=INFORMING)
    assert found.result.success
    return found.messages


@pytest.mark.parametrize("join_at", [0.0005, 2.0, 5.0005, 7.3, 9.0])
def test_a_late_subscriber_gets_what_one_there_from_the_start_got_since(join_at: float) -> None:
    early = _from_the_start()
    assert {topic for _t, topic, _m in early} == set(INFORMING)
    domain, k = _world()
    late: list[tuple[float, str, object]] = []
    subs: list[Subscription] = []

    def join(_knowledge: object, executor: Executor) -> None:
        clock = executor.hub.clock
        for topic in INFORMING:
            subs.append(
                executor.hub.subscribe(
                    topic, lambda msg, topic=topic: late.append((clock.now(), topic, msg))
                )
            )

    found = run_scenario(
        domain, k, _execute(PLAN), PERFORMERS, options=OPTIONS, events=[(join_at, join)]
    )
    assert found.result.success
    expected = [m for m in early if m[0] >= join_at]
    assert _in_order(late) == _in_order(expected)
    assert any(isinstance(m, DotGraph) for _t, _topic, m in late)


def _in_order(messages: list[tuple[float, str, object]]) -> list[object]:
    """The messages rounded (:func:`_rounded`), those of one instant in a fixed order:
    two performers' feedbacks due at the same instant reach the loop in its heap's
    order, which the timers of the run (a subscriber joining is one) move."""
    rounded = [_rounded(m) for m in messages]
    return sorted(rounded, key=lambda m: (m[0], repr(m[1:])))  # type: ignore[index]


def _rounded(item: object) -> object:
    """``item`` with its floats rounded to the microsecond (a run's loop passes, and
    with them the last bits of its virtual times, differ with who is subscribed: a
    delivery is a loop callback) and its plan ids made one."""
    if isinstance(item, float):
        return round(item, 6)
    if isinstance(item, str):  # plan ids count the plans of the process
        return re.sub(r"plan-\d+", "plan-N", item)
    if isinstance(item, tuple):
        return tuple(_rounded(x) for x in item)
    if dataclasses.is_dataclass(item) and not isinstance(item, type):
        return (type(item).__name__, _rounded(dataclasses.astuple(item)))
    return item


class _Counting(InProcessTransport):
    """Counts what is published, by topic (subscribers or not)."""

    def __init__(self) -> None:
        super().__init__()
        self.topics: dict[str, int] = {}

    def publish(self, topic: str, msg: object) -> None:
        self.topics[topic] = self.topics.get(topic, 0) + 1
        super().publish(topic, msg)


def _run_counting(listen: bool) -> tuple[_Counting, list[object]]:
    domain, k = _world()
    clock = VirtualClock()
    transport = _Counting()

    async def main() -> list[object]:
        hub = Hub(transport, clock)
        await hub.start()
        ctx = PerformerContext(hub, clock, k)
        performers = [
            SimulatedPerformer(ctx, p.name, p.actions, durations=p.durations, **p.settings)
            for p in PERFORMERS
        ]
        for p in performers:
            await p.start()
        if listen:
            for topic in INFORMING:
                hub.subscribe(topic, lambda msg: None)
        result = await Executor(hub, domain, k, None, OPTIONS).execute(PLAN)
        assert result.success
        await asyncio.sleep(0)
        records = [
            _rounded((r.text, r.status, r.start, r.end, r.performer)) for r in result.actions
        ]
        for p in performers:
            await p.stop()
        await hub.close()
        return records

    return transport, run(main(), clock)


def test_nothing_only_informing_is_published_for_nobody_and_the_mission_is_the_same() -> None:
    heard, records_heard = _run_counting(listen=True)
    alone, records_alone = _run_counting(listen=False)
    assert records_alone == records_heard
    for topic in INFORMING:
        assert heard.topics.get(topic, 0) > 0
        assert topic not in alone.topics
    # the auction and the heartbeats are the same
    assert {t: n for t, n in heard.topics.items() if t not in INFORMING} == alone.topics


def test_the_in_process_transport_knows_its_audience() -> None:
    transport = InProcessTransport()
    hub = Hub(transport)
    assert not hub.has_audience(Topics.DOT_GRAPH)
    sub = transport.subscribe(Topics.DOT_GRAPH, lambda msg: None)
    assert hub.has_audience(Topics.DOT_GRAPH) and not hub.has_audience(Topics.EXECUTING_PLAN)
    sub.close()
    assert not hub.has_audience(Topics.DOT_GRAPH)


def test_a_transport_that_cannot_tell_always_has_an_audience() -> None:
    class Plain:
        def publish(self, topic: str, msg: object) -> None: ...

        def subscribe(self, topic: str, callback: object) -> Subscription:
            raise NotImplementedError

        async def start(self) -> None: ...

        async def close(self) -> None: ...

    assert Hub(Plain()).has_audience(Topics.DOT_GRAPH)
    from plansys_bridge.hub.auth import AuthTransport

    signed = AuthTransport(InProcessTransport(), b"k" * 32)
    assert Hub(signed).has_audience(Topics.DOT_GRAPH)  # its inner transport cannot say
