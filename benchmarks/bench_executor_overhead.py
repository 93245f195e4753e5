"""The executor's own cost per action: the same plans run by performers that cost nothing.

The ring world of ``bench_graph.py`` (a fixed number of robots, crates handed from
robot to robot) is executed on the virtual clock by performers whose work takes no
time and no CPU (they accept every REQUEST for their robot and finish at once), so
what is measured is the executor: building the plan graph and the behaviour tree,
ticking it, the auctions on the hub, applying effects to the knowledge, the
execution info. The CPU time of each run is fitted as ``per_plan + per_action * n``
over the plan sizes: ``per_action`` is the executor's overhead per action.
``--parts`` then runs the largest size once more and splits its CPU time into
parts (plan graph, tree, knowledge, hub, performers: see ``executor_parts.py``)
and counts the cyclic collector's runs while it executes. Each run also times a
fixed loop of additions (:func:`reference_ms`), which shows the speed the machine
ran Python at: the same code takes about twice the time here in some stretches.
``--calls`` counts the Python function calls per action of the largest size under
cProfile: a figure that does not swing with the machine's speed. ``--instructions``
counts the machine instructions per action under valgrind's callgrind (needs
``valgrind``; a few minutes): each of the smallest and the largest size is run in a
process of its own, once executing its plan and once only making its world, with a
fixed hash seed, and the difference of the executions' differences is divided by the
difference of the sizes; the largest is run once more with the cyclic collector
paused while its plan executes, which gives the collector's share of the execution.
Why: CPU time on a shared machine swings with its neighbours (this one runs the same
code in 1x or 2x the time for seconds on end); the count of instructions does not, so
two versions of the code compare on it run after run.

Run::

    python benchmarks/bench_executor_overhead.py [--sizes 100 300 1000] [--robots 10] [--parts]
        [--calls] [--instructions]
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import gc
import os
import pstats
import re
import shutil
import subprocess
import sys
import time
from collections import Counter
from typing import Any

from bench_graph import world
from executor_parts import Parts

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionGoal, ActionPerformer, PerformerContext


class Instant(ActionPerformer):
    """Does every action it is confirmed for at once."""

    async def execute(self, goal: ActionGoal) -> str | None:
        return None


async def _run(
    actions: int,
    robots: int,
    clock: VirtualClock,
    parts: Parts | None = None,
    collect: bool = True,
    collections: Counter[int] | None = None,
) -> float:
    """CPU seconds of executing the plan; ``collect=False`` pauses the cyclic
    collector for the execution alone (not for making the world); ``collections``
    counts the collector's runs during the execution, by generation."""
    domain, knowledge, plan = world(actions, robots)
    hub = Hub(InProcessTransport(), clock)
    await hub.start()
    ctx = PerformerContext(hub, clock, knowledge)
    performers = [
        Instant(ctx, f"r{r}", {"move": [f"r{r}"], "transport": [f"r{r}"]}) for r in range(robots)
    ]
    for p in performers:
        await p.start()
    executor = Executor(hub, domain, knowledge, None, ExecutorOptions())
    timing = parts.timing() if parts is not None else contextlib.nullcontext()

    def counted(phase: str, info: dict[str, Any]) -> None:
        if phase == "start" and collections is not None:  # (None: not registered)
            collections[info["generation"]] += 1

    if not collect:
        gc.disable()
    if collections is not None:
        gc.callbacks.append(counted)
    try:
        c0 = time.process_time()
        with timing:
            result = await executor.execute(plan)
        cpu = time.process_time() - c0
    finally:
        if collections is not None:
            gc.callbacks.remove(counted)
        if not collect:
            gc.enable()
    for p in performers:
        await p.stop()
    await hub.close()
    if not result.success:
        raise RuntimeError(f"{actions} actions: {result.status}: {result.message}")
    return cpu


def measure(actions: int, robots: int, repeat: int) -> dict[str, Any]:
    best = float("inf")
    for _ in range(repeat):
        # The previous run's plan, tree and hub are garbage with cycles: collected
        # now, so a run pays for the collections its own allocations cause and not
        # for a full collection of the run before (0.15-0.2 s of 1000 actions).
        gc.collect()
        clock = VirtualClock()
        best = min(best, run(_run(actions, robots, clock), clock))
    return {"actions": actions, "robots": robots, "cpu_s": best}


_REFERENCE_ADDITIONS = 2_000_000


def reference_ms() -> float:
    """CPU milliseconds of a fixed loop of additions (best of three): the speed the
    machine ran Python at in this run. Why: the target is in milliseconds, and this
    machine runs the same code at two speeds (its neighbours' load) for seconds or
    minutes on end; the loop's time says which one a run saw."""
    best = float("inf")
    for _ in range(3):
        c0 = time.process_time()
        total = 0
        for i in range(_REFERENCE_ADDITIONS):
            total += i
        best = min(best, time.process_time() - c0)
    return best * 1e3


def fit(rows: list[dict[str, Any]]) -> tuple[float, float]:
    """Least squares ``cpu = per_plan + per_action * actions``."""
    xs = [r["actions"] for r in rows]
    ys = [r["cpu_s"] for r in rows]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sxx
    return my - slope * mx, slope


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 300, 1000])
    parser.add_argument("--robots", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=2, help="runs per size (best kept)")
    parser.add_argument("--parts", action="store_true", help="split the largest run's CPU time")
    parser.add_argument(
        "--calls", action="store_true", help="Python function calls per action (cProfile)"
    )
    parser.add_argument(
        "--instructions",
        action="store_true",
        help="machine instructions per action (valgrind's callgrind, a few minutes)",
    )
    parser.add_argument("--one-run", nargs=2, metavar=("ACTIONS", "WHAT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one_run:  # a child of --instructions: one run, counted from outside
        one_run(int(args.one_run[0]), args.robots, args.one_run[1])
        return
    rows = [measure(n, args.robots, args.repeat) for n in args.sizes]
    print(f"Executor CPU time with performers that cost nothing, {args.robots} robots")
    print(f"{'actions':>8} {'cpu s':>8} {'ms/action':>10}")
    for r in rows:
        print(f"{r['actions']:>8} {r['cpu_s']:>8.3f} {r['cpu_s'] / r['actions'] * 1e3:>10.3f}")
    if len({r["actions"] for r in rows}) > 1:
        per_plan, per_action = fit(rows)
        print(
            f"fit: {per_plan * 1e3:.1f} ms per plan + {per_action * 1e3:.3f} ms per action "
            "(target: < 0.2 ms per action)"
        )
    else:
        print("fit: needs two sizes or more (--sizes 100 1000)")
    print(
        f"machine speed in this run: a plain Python loop of {_REFERENCE_ADDITIONS:,} additions "
        f"took {reference_ms():.0f} ms (best of 3)"
    )
    if args.parts:
        print_parts(max(args.sizes), args.robots)
    if args.calls:
        print_calls(max(args.sizes), args.robots)
    if args.instructions:
        print_instructions(min(args.sizes), max(args.sizes), args.robots)


def print_calls(actions: int, robots: int) -> None:
    profile = cProfile.Profile()
    clock = VirtualClock()
    profile.runcall(run, _run(actions, robots, clock), clock)
    stats = pstats.Stats(profile)
    calls = stats.total_calls  # type: ignore[attr-defined]
    # asyncio's own Python code (scheduling callbacks and timers, futures, tasks):
    # what the loop costs, apart from what the executor asks of it
    loop_calls = sum(
        counts[1]
        for (filename, _line, _name), counts in stats.stats.items()  # type: ignore[attr-defined]
        if f"{os.sep}asyncio{os.sep}" in filename
    )
    print(
        f"Python function calls (cProfile), {actions} actions: {calls / actions:.0f} per action, "
        f"{loop_calls / actions:.0f} of them in asyncio's own code"
    )


def one_run(actions: int, robots: int, what: str) -> None:
    """``execute``: make the world and execute its plan; ``paused``: the same with
    the cyclic collector paused while the plan executes (making the world collects
    as in the others, so the difference is the execution's collections alone);
    ``world``: only make the world."""
    if what == "world":
        world(actions, robots)
        return
    gc.collect()
    clock = VirtualClock()
    run(_run(actions, robots, clock, collect=what != "paused"), clock)


def _instructions(actions: int, robots: int, what: str) -> int:
    """Instructions callgrind counts in a process making one run."""
    command = [
        "valgrind",
        "--tool=callgrind",
        "--callgrind-out-file=/dev/null",
        sys.executable,
        os.path.abspath(__file__),
        "--robots",
        str(robots),
        "--one-run",
        str(actions),
        what,
    ]
    env = dict(os.environ, PYTHONHASHSEED="0")
    done = subprocess.run(command, capture_output=True, text=True, env=env, check=False)
    found = re.search(r"Collected : (\d+)", done.stderr)
    if done.returncode != 0 or found is None:
        raise RuntimeError(f"{' '.join(command)} failed ({done.returncode}): {done.stderr[-800:]}")
    return int(found.group(1))


def print_instructions(small: int, large: int, robots: int) -> None:
    if shutil.which("valgrind") is None:
        print("instructions: needs valgrind on PATH (apt-get install valgrind)")
        return
    if small == large:
        print("instructions: needs two sizes or more (--sizes 100 1000)")
        return
    made = {n: _instructions(n, robots, "world") for n in (small, large)}
    executed = {n: _instructions(n, robots, "execute") - made[n] for n in (small, large)}
    paused = _instructions(large, robots, "paused") - made[large]
    per_action = (executed[large] - executed[small]) / (large - small)
    print(
        f"machine instructions (callgrind): {executed[small] / 1e6:.1f} M executing {small} "
        f"actions, {executed[large] / 1e6:.1f} M executing {large}: "
        f"{per_action / 1e3:.0f} k per action; {paused / 1e6:.1f} M executing {large} with "
        f"the cyclic collector paused (its share {1 - paused / executed[large]:.0%})"
    )


def print_parts(actions: int, robots: int) -> None:
    parts = Parts()
    collections: Counter[int] = Counter()
    gc.collect()
    clock = VirtualClock()
    run(_run(actions, robots, clock, parts, collections=collections), clock)
    print(f"where the CPU time of {actions} actions goes (exclusive, ms per action):")
    for part, seconds in parts.seconds.most_common():
        print(f"  {seconds / actions * 1e3:7.3f}  {part}")
    print(f"  {sum(parts.seconds.values()) / actions * 1e3:7.3f}  total (timing included)")
    print(
        "cyclic collections while executing, by generation: "
        + ", ".join(f"{g}: {collections[g]}" for g in range(3))
    )


if __name__ == "__main__":
    main()
