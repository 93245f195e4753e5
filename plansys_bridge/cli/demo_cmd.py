"""``plansys-bridge demo``: the main demo mission, on embedded defaults.

No hardware, no servers: the cooking world with three simulated robots, a battery
drop that forces a replan, on the wall clock 10x faster than mission time.
"""

from __future__ import annotations

import argparse
from typing import Any

from plansys_bridge.cli import run_cmd

DEMOS = {
    "cooking": "demo_cooking.yaml",
}


def register(sub: Any) -> None:
    p = sub.add_parser("demo", help="run a demo mission (default: cooking, 3 robots, a replan)")
    p.add_argument("name", nargs="?", default="cooking", choices=sorted(DEMOS))
    p.add_argument("--clock", choices=("wall", "virtual"), help="override the demo's clock")
    p.add_argument("--time-scale", type=float, help="override the wall clock's time scale")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    run_cmd.add_report_option(p)
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    """Run the demo's mission file exactly as ``plansys-bridge run`` would."""
    from plansys_bridge.mission import default_missions_dir

    argv = ["run", str(default_missions_dir() / DEMOS[args.name])]
    if args.clock:
        argv += ["--clock", args.clock]
    if args.time_scale is not None:
        argv += ["--time-scale", str(args.time_scale)]
    if args.json:
        argv.append("--json")
    if args.report:
        argv += ["--report", args.report]
    if getattr(args, "quiet", False):
        argv.append("--quiet")
    argv += ["--verbose"] * int(getattr(args, "verbose", 0) or 0)
    parser = argparse.ArgumentParser(prog="plansys-bridge")
    run_cmd.register(parser.add_subparsers())
    run_args = parser.parse_args(argv)
    code: int = run_args.func(run_args)
    return code
