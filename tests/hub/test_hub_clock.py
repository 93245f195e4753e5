"""The virtual clock runs hours of asyncio time in moments, deterministically."""

from __future__ import annotations

import asyncio
import random
import threading
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, VirtualTimeEventLoop, WallClock, run


def test_two_hours_of_sleep_take_under_a_second_of_wall_time() -> None:
    async def sleeper(n: int) -> int:
        for _ in range(n):
            await asyncio.sleep(1.0)
        return n

    async def main() -> tuple[float, list[int]]:
        # one task sleeping second by second, another the whole two hours at once
        results = await asyncio.gather(sleeper(7200), asyncio.sleep(7200.0, result=1))
        return asyncio.get_running_loop().time(), results

    started = time.perf_counter()
    now, results = run(main(), VirtualClock())
    wall = time.perf_counter() - started
    assert now == 7200.0
    assert results == [7200, 1]
    assert wall < 1.0, f"2 h of virtual sleeps took {wall:.2f} s of wall time"


def _scenario(seed: int) -> list[tuple[float, str]]:
    rng = random.Random(seed)
    delays = {f"t{i}": [rng.choice([0.0, 0.5, 1.0, 2.5]) for _ in range(20)] for i in range(6)}
    events: list[tuple[float, str]] = []

    async def worker(name: str, steps: list[float]) -> None:
        loop = asyncio.get_running_loop()
        for k, d in enumerate(steps):
            await asyncio.sleep(d)
            events.append((loop.time(), f"{name}.{k}"))

    async def main() -> None:
        loop = asyncio.get_running_loop()
        loop.call_later(3.0, lambda: events.append((loop.time(), "timer")))
        await asyncio.gather(*(worker(n, s) for n, s in delays.items()))

    run(main(), VirtualClock())
    return events


def test_order_and_times_are_deterministic() -> None:
    first = _scenario(7)
    assert first == _scenario(7)
    assert [t for t, _ in first] == sorted(t for t, _ in first)
    assert (3.0, "timer") in first


def test_timeouts_fire_at_exact_virtual_times() -> None:
    async def main() -> list[float]:
        loop = asyncio.get_running_loop()
        seen: list[float] = []
        try:
            await asyncio.wait_for(asyncio.sleep(10.0), timeout=5.0)
        except TimeoutError:
            seen.append(loop.time())
        fired = loop.create_future()
        loop.call_at(100.0, fired.set_result, None)
        await fired
        seen.append(loop.time())
        await asyncio.sleep(3 * 24 * 3600)  # longer than asyncio's 24 h select cap
        seen.append(loop.time())
        return seen

    assert run(main(), VirtualClock()) == [5.0, 100.0, 100.0 + 3 * 24 * 3600]


def test_virtual_clock_starts_where_asked_and_reports_loop_time() -> None:
    clock = VirtualClock(start=1000.0)

    async def main() -> tuple[float, float]:
        before = clock.now()
        await clock.sleep(2.5)
        return before, clock.now()

    assert run(main(), clock) == (1000.0, 1002.5)
    assert clock.time_scale == 1.0


def test_time_holds_still_while_executor_work_runs() -> None:
    async def main() -> tuple[float, bool, float]:
        loop = asyncio.get_running_loop()
        timer = asyncio.ensure_future(asyncio.sleep(1.0))
        await loop.run_in_executor(None, time.sleep, 0.05)
        during = loop.time()
        timer_done_during = timer.done()
        await timer
        return during, timer_done_during, loop.time()

    during, timer_done, after = run(main(), VirtualClock())
    assert during == 0.0
    assert not timer_done
    assert after == 1.0


def test_threadsafe_wakeup_is_not_starved_by_virtual_timers() -> None:
    async def main() -> tuple[str, float]:
        loop = asyncio.get_running_loop()
        box: asyncio.Future[str] = loop.create_future()

        def later() -> None:
            time.sleep(0.02)
            loop.call_soon_threadsafe(box.set_result, "hi")

        thread = threading.Thread(target=later)
        thread.start()
        try:
            value = await box  # no timer pending: the loop waits for the real event
        finally:
            await loop.run_in_executor(None, thread.join)
        return value, loop.time()

    assert run(main(), VirtualClock()) == ("hi", 0.0)


def test_virtual_sleep_needs_the_virtual_loop() -> None:
    async def main() -> None:
        await VirtualClock().sleep(1.0)

    with pytest.raises(RuntimeError, match="VirtualTimeEventLoop"):
        asyncio.run(main())


def test_manual_advance_moves_time_forward_only() -> None:
    loop = VirtualTimeEventLoop()
    try:
        loop.advance(2.0)
        assert loop.time() == 2.0
        with pytest.raises(ValueError):
            loop.advance(-1.0)
    finally:
        loop.close()


def test_wall_clock_scales_mission_time() -> None:
    clock = WallClock(time_scale=0.01)

    async def main() -> tuple[float, float]:
        before = clock.now()
        real = time.monotonic()
        await clock.sleep(1.0)  # 10 ms of real time
        return clock.now() - before, time.monotonic() - real

    mission, real = run(main(), clock)
    assert mission >= 1.0 - 1e-6
    assert real >= 0.01 - 1e-3
    with pytest.raises(ValueError):
        WallClock(time_scale=0)


def _reference_now(clock: VirtualClock) -> float:
    """``VirtualClock.now`` as it reads without its remembered loop."""
    try:
        running: asyncio.AbstractEventLoop | None = asyncio.get_running_loop()
    except RuntimeError:
        running = None
    if isinstance(running, VirtualTimeEventLoop):
        return running.time()
    return clock.loop.time() if clock.loop is not None else clock._start


@given(
    start=st.floats(0.0, 1e6),
    runs=st.lists(
        st.tuples(
            st.sampled_from(["virtual", "plain"]),
            st.lists(
                st.tuples(st.sampled_from(["sleep", "advance"]), st.floats(0, 50)), max_size=4
            ),
        ),
        max_size=4,
    ),
)
@settings(max_examples=60, deadline=None)
def test_now_from_the_remembered_loop_equals_the_general_reading(
    start: float, runs: list[tuple[str, list[tuple[str, float]]]]
) -> None:
    clock = VirtualClock(start)
    seen: list[tuple[float, float]] = []

    def read() -> None:
        seen.append((clock.now(), _reference_now(clock)))

    async def virtual(steps: list[tuple[str, float]]) -> None:
        loop = asyncio.get_running_loop()
        assert isinstance(loop, VirtualTimeEventLoop)
        read()
        for kind, seconds in steps:
            if kind == "sleep":
                await asyncio.sleep(seconds)
            else:
                loop.advance(seconds)
            read()

    async def plain() -> None:
        read()  # a loop of another kind: the last virtual loop's time

    read()  # before any loop
    for kind, steps in runs:
        if kind == "virtual":
            run(virtual(steps), clock)
        else:
            asyncio.run(plain())
        read()  # between loops
    assert all(fast == general for fast, general in seen), seen


def test_a_loop_with_its_own_time_is_asked_every_time() -> None:
    asked: list[float] = []

    class Watched(VirtualTimeEventLoop):
        def time(self) -> float:
            now = super().time() + 0.25
            asked.append(now)
            return now

    clock = VirtualClock()

    async def read() -> tuple[float, bool]:
        before = len(asked)
        now = clock.now()
        return now, len(asked) > before

    assert run(read(), clock) == (0.0, False)
    with asyncio.Runner(loop_factory=Watched) as runner:
        assert runner.run(read()) == (0.25, True)
        assert runner.run(read()) == (0.25, True)  # asked again, not remembered
    assert run(read(), clock) == (0.0, False)  # and a plain virtual loop again


@settings(max_examples=100, deadline=None)
@given(steps=st.lists(st.one_of(st.floats(0, 50), st.just("sleep")), max_size=8))
def test_the_loops_time_reads_its_virtual_time(steps: list[float | str]) -> None:
    """``time()`` is bound per loop as an attribute read: it must say what the class's
    method says, after jumps and manual advances alike."""

    async def main() -> None:
        loop = asyncio.get_running_loop()
        assert isinstance(loop, VirtualTimeEventLoop)
        for step in steps:
            if step == "sleep":
                await asyncio.sleep(1.5)
            else:
                assert isinstance(step, float)
                loop.advance(step)
            assert loop.time() == VirtualTimeEventLoop.time(loop) == loop._virtual_now

    run(main(), VirtualClock(start=2.0))


def test_a_loop_class_with_its_own_time_keeps_it(monkeypatch: pytest.MonkeyPatch) -> None:
    class Shifted(VirtualTimeEventLoop):
        def time(self) -> float:
            return self._virtual_now + 100.0

    shifted = Shifted(start=1.0)
    monkeypatch.setattr(VirtualTimeEventLoop, "time", lambda self: -1.0)
    patched = VirtualTimeEventLoop(start=1.0)
    try:
        assert shifted.time() == 101.0
        assert patched.time() == -1.0
    finally:
        shifted.close()
        patched.close()
