"""``plansys-bridge report RECORDING --out DIR``: pictures and summary of a recorded run.

The same files ``run --report DIR`` writes (Gantt chart as SVG and PNG, plan graph
as DOT and SVG, ``summary.json``), drawn from a bag written by ``--record``. A
recording does not say how the run ended, so the outcome is read from it: the run
succeeded when every action of its last plan did.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from plansys_bridge.cli.output import say


def register(sub: Any) -> None:
    p = sub.add_parser(
        "report",
        help="draw the Gantt chart, plan graph and summary of a recorded mission",
    )
    p.add_argument("recording", help="mission bag folder written by --record")
    p.add_argument("--out", required=True, metavar="DIR", help="folder for the report files")
    p.add_argument(
        "--no-graphviz",
        action="store_true",
        help="lay the plan graph out in Python even when Graphviz is installed",
    )
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    from plansys_bridge.report.model import RunReport
    from plansys_bridge.report.recording import watch_recording
    from plansys_bridge.report.write import write_report

    watch, first, last = watch_recording(args.recording)
    final = watch.plans[-1].actions if watch.plans else []
    success = bool(final) and all(a.status.name == "SUCCEEDED" for a in final)
    report = RunReport.from_watch(
        watch,
        name=Path(args.recording).name,
        status="succeeded" if success else "failed",
        success=success,
        started=watch.plans[0].stamp if watch.plans else first,
        finished=last,
    )
    for path in write_report(report, args.out, use_graphviz=not args.no_graphviz):
        say(str(path))
    return 0
