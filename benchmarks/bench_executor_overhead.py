"""The executor's own cost per action: the same plans run by performers that cost nothing.

The ring world of ``bench_graph.py`` (a fixed number of robots, crates handed from
robot to robot) is executed on the virtual clock by performers whose work takes no
time and no CPU (they accept every REQUEST for their robot and finish at once), so
what is measured is the executor: building the plan graph and the behaviour tree,
ticking it, the auctions on the hub, applying effects to the knowledge, the
execution info. The CPU time of each run is fitted as ``per_plan + per_action * n``
over the plan sizes: ``per_action`` is the executor's overhead per action.

Run::

    python benchmarks/bench_executor_overhead.py [--sizes 100 300 1000] [--robots 10]
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from bench_graph import world

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


async def _run(actions: int, robots: int, clock: VirtualClock) -> float:
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
    c0 = time.process_time()
    result = await executor.execute(plan)
    cpu = time.process_time() - c0
    for p in performers:
        await p.stop()
    await hub.close()
    if not result.success:
        raise RuntimeError(f"{actions} actions: {result.status}: {result.message}")
    return cpu


def measure(actions: int, robots: int, repeat: int) -> dict[str, Any]:
    best = float("inf")
    for _ in range(repeat):
        clock = VirtualClock()
        best = min(best, run(_run(actions, robots, clock), clock))
    return {"actions": actions, "robots": robots, "cpu_s": best}


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
    args = parser.parse_args()
    rows = [measure(n, args.robots, args.repeat) for n in args.sizes]
    print(f"Executor CPU time with performers that cost nothing, {args.robots} robots")
    print(f"{'actions':>8} {'cpu s':>8} {'ms/action':>10}")
    for r in rows:
        print(f"{r['actions']:>8} {r['cpu_s']:>8.3f} {r['cpu_s'] / r['actions'] * 1e3:>10.3f}")
    per_plan, per_action = fit(rows)
    print(
        f"fit: {per_plan * 1e3:.1f} ms per plan + {per_action * 1e3:.3f} ms per action "
        "(target: < 0.2 ms per action)"
    )


if __name__ == "__main__":
    main()
