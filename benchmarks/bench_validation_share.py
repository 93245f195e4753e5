"""What share of knowledge -> plan the plan check takes.

For each task of ``bench_planners.py`` (quick set): the time of ``Planner.solve``
with validation on, as ``plansys-bridge plan`` does (capability check, writing the PDDL, the
embedded solver, reading its plan, checking it) and, on its own, ``validate_plan``
of the plan found; the share is the second over the first. Best of ``--repeat``
runs each, the two taken in turn (a shared machine only adds time, and its speed
drifts: measured in turn, both see the same stretches).

Run: ``python benchmarks/bench_validation_share.py [--repeat 5] [--json]``
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any

from bench_planners import build_tasks

from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.validation import validate_plan


def _best_of_each(first: Any, second: Any, repeat: int) -> tuple[float, float]:
    """The best time of each, run in turn: on a shared machine whose speed drifts, both
    are measured in the same stretches of time, so their ratio does not depend on
    which one happened to run during a slow one."""
    best = [math.inf, math.inf]
    for _ in range(repeat):
        for i, fn in enumerate((first, second)):
            t0 = time.perf_counter()
            fn()
            best[i] = min(best[i], time.perf_counter() - t0)
    return best[0], best[1]


def measure(repeat: int) -> list[dict[str, Any]]:
    rows = []
    planner = Planner(validate=True)
    for task in build_tasks(quick=True):
        result = planner.solve(task.domain, task.problem)
        if result.plan is None:
            continue
        plan = result.plan
        solve_s, check_s = _best_of_each(
            lambda t=task: planner.solve(t.domain, t.problem),
            lambda t=task, p=plan: validate_plan(t.domain, t.problem, p),
            repeat,
        )
        rows.append(
            {
                "task": task.name,
                "steps": len(plan),
                "plan_ms": solve_s * 1e3,
                "validate_ms": check_s * 1e3,
                "share_percent": 100 * check_s / solve_s,
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = measure(args.repeat)
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    print(f"{'task':<22} {'steps':>5} {'plan ms':>9} {'validate ms':>12} {'share %':>8}")
    for r in rows:
        print(
            f"{r['task']:<22} {r['steps']:>5} {r['plan_ms']:>9.1f} {r['validate_ms']:>12.1f} "
            f"{r['share_percent']:>8.1f}"
        )


if __name__ == "__main__":
    main()
