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
time should grow in proportion to the plan length (the last column: CPU time per
action relative to the smallest size; CPU time is less disturbed than wall time by
other work on a shared machine).
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
        t0, c0 = time.perf_counter(), time.process_time()
        result = await executor.execute(plan)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
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
            "cpu_s": cpu,
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
    head: tuple[str, ...] = ("actions", "robots", "planned s", "mission s", "wall s", "cpu s")
    head += ("eff %", "cpu ms/act", "x first")
    print(" ".join(f"{h:>10}" for h in head))
    first = rows[0]["cpu_s"] / rows[0]["actions"]
    for r in rows:
        per_action = r["cpu_s"] / r["actions"]
        print(
            f"{r['actions']:>10} {r['robots']:>10} {r['planned_makespan_s']:>10.1f} "
            f"{r['mission_time_s']:>10.1f} {r['wall_s']:>10.2f} {r['cpu_s']:>10.2f} "
            f"{r['efficiency_percent']:>10.0f} {per_action * 1e3:>10.3f} "
            f"{per_action / first:>10.2f}"
        )


if __name__ == "__main__":
    main()
