"""One loop timer for the deadlines of many auction clients (hub/alarms.py)."""

from __future__ import annotations

import asyncio
import gc
import weakref
from typing import Any

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.alarms import Alarms, alarms_of


class Sleeper:
    """Notes when its alarm rang, in a shared list."""

    _alarm = 0

    def __init__(self, name: str, rang: list[tuple[str, float]], fail: bool = False) -> None:
        self.name, self.rang, self.fail = name, rang, fail
        self.then: Any = None

    def _on_timer(self) -> None:
        self.rang.append((self.name, asyncio.get_running_loop().time()))
        if self.then is not None:
            self.then()
        if self.fail:
            raise RuntimeError(f"{self.name} failed")


def _in_loop(body: Any) -> Any:
    clock = VirtualClock()

    async def main() -> Any:
        return await body(asyncio.get_running_loop())

    return run(main(), clock)


def test_alarms_ring_at_their_deadline_earliest_first_then_in_order_set() -> None:
    async def body(loop: asyncio.AbstractEventLoop) -> list[tuple[str, float]]:
        alarms = alarms_of(loop)
        rang: list[tuple[str, float]] = []
        for name, when in [("c", 3.0), ("a", 1.0), ("b", 1.0), ("d", 2.5)]:
            alarms.set(when, Sleeper(name, rang))
        await asyncio.sleep(5.0)
        return rang

    assert _in_loop(body) == [("a", 1.0), ("b", 1.0), ("d", 2.5), ("c", 3.0)]


def test_a_forgotten_or_replaced_alarm_does_not_ring() -> None:
    async def body(loop: asyncio.AbstractEventLoop) -> list[tuple[str, float]]:
        alarms = alarms_of(loop)
        rang: list[tuple[str, float]] = []
        gone, moved, kept = Sleeper("gone", rang), Sleeper("moved", rang), Sleeper("kept", rang)
        alarms.set(1.0, gone)
        alarms.set(1.0, moved)
        alarms.set(2.0, kept)
        Alarms.clear(gone)
        alarms.set(4.0, moved)  # replaces its alarm at 1.0
        await asyncio.sleep(5.0)
        return rang

    assert _in_loop(body) == [("kept", 2.0), ("moved", 4.0)]


def test_an_alarm_set_while_ringing_rings_later_and_errors_reach_the_handler() -> None:
    async def body(loop: asyncio.AbstractEventLoop) -> tuple[list[tuple[str, float]], list[str]]:
        alarms = alarms_of(loop)
        rang: list[tuple[str, float]] = []
        errors: list[str] = []
        loop.set_exception_handler(lambda _loop, ctx: errors.append(str(ctx["exception"])))
        first, again = Sleeper("first", rang, fail=True), Sleeper("again", rang)
        first.then = lambda: alarms.set(loop.time(), again)  # due at once: not this pass
        alarms.set(1.0, first)
        alarms.set(1.5, Sleeper("third", rang))
        await asyncio.sleep(3.0)
        return rang, errors

    rang, errors = _in_loop(body)
    assert rang == [("first", 1.0), ("again", 1.0), ("third", 1.5)]
    assert errors == ["first failed"]


def test_an_earlier_alarm_moves_the_loop_timer_earlier() -> None:
    async def body(loop: asyncio.AbstractEventLoop) -> list[tuple[str, float]]:
        alarms = alarms_of(loop)
        rang: list[tuple[str, float]] = []
        alarms.set(10.0, Sleeper("late", rang))
        await asyncio.sleep(1.0)
        alarms.set(2.0, Sleeper("early", rang))
        await asyncio.sleep(10.0)
        return rang

    assert _in_loop(body) == [("early", 2.0), ("late", 10.0)]


def test_forgotten_alarms_do_not_hold_their_clients() -> None:
    async def body(loop: asyncio.AbstractEventLoop) -> tuple[bool, int]:
        alarms = alarms_of(loop)
        rang: list[tuple[str, float]] = []
        ended = [Sleeper(f"s{i}", rang) for i in range(100)]
        for s in ended:
            alarms.set(60.0, s)
            Alarms.clear(s)  # as a client that ended before its deadline
        refs = [weakref.ref(s) for s in ended]
        del ended, s
        alarms.set(60.0, Sleeper("next", rang))  # setting drops the stale heads
        gc.collect()
        return all(r() is None for r in refs), len(alarms)

    freed, held = _in_loop(body)
    assert freed and held == 1


def test_each_loop_has_its_own_alarms() -> None:
    async def body(loop: asyncio.AbstractEventLoop) -> Alarms:
        return alarms_of(loop)

    first, second = _in_loop(body), _in_loop(body)
    assert first is not second
    assert first.loop() is None or first.loop() is not second.loop()
