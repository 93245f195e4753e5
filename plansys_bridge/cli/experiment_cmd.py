"""``plansys-bridge experiment cooking``: the PlanSys2 paper's cooking experiment."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

from plansys_bridge.cli.options import check_at_least, check_non_negative, check_positive

if TYPE_CHECKING:
    from plansys_bridge.execution.results import ExecutionResult


def register(sub: Any) -> None:
    p = sub.add_parser("experiment", help="run a reproducible experiment (cooking)")
    p.add_argument("name", choices=("cooking",))
    p.add_argument("--robots", type=int, default=3, choices=(1, 2, 3, 4, 5, 6))
    p.add_argument("--hours", type=float, default=1.0, help="mission time, at the paper's scale")
    p.add_argument("--plans", type=int, help="stop after this many missions instead of --hours")
    p.add_argument("--clock", choices=("virtual", "wall"), default="virtual")
    p.add_argument(
        "--time-scale",
        type=float,
        default=1.0,
        help="wall clock: real seconds per mission second (0.05 runs 20x faster)",
    )
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--battery-drops", type=float, default=2.0, help="per robot per hour")
    p.add_argument("--max-replans", type=int, default=5)
    p.add_argument(
        "--faults",
        action="store_true",
        help="soak: performers die and revive, FINISH lost, performers stop answering",
    )
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--progress", action="store_true", help="one line per mission on stderr")
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    check_positive(args.time_scale, "--time-scale")
    check_positive(args.hours, "--hours")
    check_at_least(args.plans, 1, "--plans")
    check_non_negative(args.battery_drops, "--battery-drops")
    # imported here: `--help` and the other commands never pay for the experiment
    from plansys_bridge.experiments.cooking import PAPER_EFFICIENCY, CookingConfig, run_cooking
    from plansys_bridge.performers.simulated import FaultPlan

    faults = FaultPlan()
    unresponsive = 0.0
    if args.faults:
        faults = FaultPlan(die_rate=0.01, lose_finish_rate=0.01, revive_after=20.0)
        unresponsive = 1.0

    def progress(number: int, result: ExecutionResult) -> None:
        print(
            f"mission {number}: {result.status}, {len(result.actions)} actions, "
            f"{result.replans} replans",
            file=sys.stderr,
        )

    config = CookingConfig(
        robots=args.robots,
        hours=args.hours,
        max_plans=args.plans,
        clock=args.clock,
        time_scale=args.time_scale if args.clock == "wall" else 1.0,
        seed=args.seed,
        battery_drops_per_hour=args.battery_drops,
        max_replans=args.max_replans,
        faults=faults,
        unresponsive_per_hour=unresponsive,
        on_plan=progress if args.progress else None,
    )
    stats = run_cooking(config)
    data = stats.to_json()
    paper = PAPER_EFFICIENCY.get(args.robots)
    data["paper_efficiency_percent"] = paper
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        print(f"cooking experiment, {args.robots} robot(s), {args.clock} clock")
        for key in (
            "missions",
            "plans",
            "actions",
            "replans",
            "failures",
            "dishes",
            "battery_drops",
            "total_time_s",
            "efficiency_percent",
            "planning_s",
            "wall_s",
        ):
            print(f"  {key:<20} {data[key]}")
        if paper is not None:
            print(f"  {'paper (Table I)':<20} {paper} %")
        if stats.consistency_errors:
            print(f"  consistency errors: {stats.consistency_errors[:5]}")
    return 0 if not stats.consistency_errors else 1
