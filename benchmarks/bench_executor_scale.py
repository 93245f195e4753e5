"""Executing large plans on the virtual clock: does the executor keep up?

The ring world of ``bench_graph.py`` (one robot per 20 actions, crates handed from
robot to robot), one simulated performer per robot, the virtual clock. For each plan
size it prints the mission time the execution took (it equals the planned makespan
when every action starts the moment its dependencies allow), the wall time the
whole run cost (graph, tree, every tick, every auction message), and the paper's
efficiency metric (summed action time over total time, so about 100 % per robot).

Run::

    python benchmarks/bench_executor_scale.py [--sizes 100 500 1000 5000] [--robots N] [--json]

With ``--robots`` fixed, the work per action is the same at every size, so the wall
time should grow in proportion to the plan length (the last column: wall time per
action relative to the smallest size).
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

from bench_graph import world

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer


def measure(
    actions: int, robots: int | None = None, options: ExecutorOptions | None = None
) -> dict[str, Any]:
    domain, knowledge, plan = world(actions, robots)
    robots = robots if robots is not None else max(1, actions // 20)
    clock = VirtualClock()

    async def main() -> dict[str, Any]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        ctx = PerformerContext(hub, clock, knowledge)
        performers = [
            SimulatedPerformer(
                ctx,
                f"r{r}",
                {"move": [f"r{r}"], "transport": [f"r{r}"]},
                durations={"move": 4.0, "transport": 6.0},
                feedback_period=None,
            )
            for r in range(robots)
        ]
        for p in performers:
            await p.start()
        executor = Executor(hub, domain, knowledge, None, options or ExecutorOptions())
        t0 = time.perf_counter()
        result = await executor.execute(plan)
        wall = time.perf_counter() - t0
        for p in performers:
            await p.stop()
        await hub.close()
        if not result.success:
            raise RuntimeError(f"{actions} actions: {result.status}: {result.message}")
        return {
            "actions": actions,
            "robots": robots,
            "planned_makespan_s": plan.makespan,
            "mission_time_s": result.total_time,
            "wall_s": wall,
            "efficiency_percent": result.efficiency_percent,
        }

    return run(main(), clock)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 500, 1000, 5000])
    parser.add_argument(
        "--robots", type=int, help="a fixed robot count (default: one robot per 20 actions)"
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = [measure(n, args.robots) for n in args.sizes]
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    head: tuple[str, ...] = ("actions", "robots", "planned s", "mission s", "wall s", "eff %")
    head += ("ms/action", "x first")
    print(" ".join(f"{h:>10}" for h in head))
    first = rows[0]["wall_s"] / rows[0]["actions"]
    for r in rows:
        per_action = r["wall_s"] / r["actions"]
        print(
            f"{r['actions']:>10} {r['robots']:>10} {r['planned_makespan_s']:>10.1f} "
            f"{r['mission_time_s']:>10.1f} {r['wall_s']:>10.2f} {r['efficiency_percent']:>10.0f} "
            f"{per_action * 1e3:>10.3f} {per_action / first:>10.2f}"
        )


if __name__ == "__main__":
    main()
