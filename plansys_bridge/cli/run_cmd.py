"""``plansys-bridge run MISSION.yaml``: run a mission file to its end."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

from plansys_bridge.cli.options import check_positive
from plansys_bridge.cli.output import say
from plansys_bridge.cli.verbosity import add_verbosity
from plansys_bridge.errors import ConfigError
from plansys_bridge.textfile import read_text

if TYPE_CHECKING:
    from plansys_bridge.mission import MissionReport
    from plansys_bridge.planning.plan import Plan


def register(sub: Any) -> None:
    p = sub.add_parser("run", help="run a mission file (domain, knowledge, goal, performers)")
    p.add_argument("mission", help="mission YAML file (see configs/)")
    p.add_argument("--plan", help="execute this plan file instead of planning first")
    p.add_argument("--clock", choices=("wall", "virtual"), help="override the mission's clock")
    p.add_argument("--time-scale", type=float, help="override clock.time_scale (wall clock)")
    p.add_argument("--record", help="record the run to this ROS 2 bag folder (mcap)")
    p.add_argument(
        "--no-performers",
        action="store_true",
        help="run the executor only; the performers run in other processes "
        "(`plansys-bridge performers`, needs transport: {kind: dds})",
    )
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_report_option(p)
    add_verbosity(p)
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    check_positive(args.time_scale, "--time-scale")
    # imported here: `--help` and the other commands never pay for missions
    from plansys_bridge.mission import run_mission
    from plansys_bridge.mission_config import load_mission
    from plansys_bridge.planning.plan import parse_plan

    mission = load_mission(args.mission)
    updates: dict[str, Any] = {}
    if args.clock or args.time_scale is not None:
        clock = mission.clock.model_dump() | {
            k: v
            for k, v in (("kind", args.clock), ("time_scale", args.time_scale))
            if v is not None
        }
        if clock["kind"] == "virtual":
            if args.time_scale is not None:
                raise ConfigError(
                    "applies to the wall clock; the virtual clock skips idle time",
                    key="--time-scale",
                )
            clock["time_scale"] = 1.0
        updates["clock"] = type(mission.clock).model_validate(clock)
    if args.record:
        updates["record"] = args.record
    if updates:
        mission = mission.model_copy(update=updates)
    plan: Plan | None = None
    if args.plan:
        plan = parse_plan(read_text(args.plan, "plan file"), args.plan)
    quiet = args.quiet or args.json
    report = run_mission(
        mission,
        out=None if quiet else say,
        plan=plan,
        local_performers=not args.no_performers,
        live=not quiet and sys.stdout.isatty(),
    )
    if args.json:
        say(json.dumps(report_json(report), indent=2))
    else:
        say(report.summary())
    if getattr(args, "report", None):
        for path in write_run_report(report, args.report):
            if not quiet:
                say(f"wrote {path}")
    return 0 if report.success else 1


def add_report_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--report",
        metavar="DIR",
        help="write gantt.svg/.png, plan_graph.dot/.svg and summary.json into DIR",
    )


def write_run_report(report: MissionReport, folder: str) -> list[Any]:
    """The report files of a run just finished (see :mod:`plansys_bridge.report`)."""
    from plansys_bridge.report.model import RunReport
    from plansys_bridge.report.write import write_report

    if report.watch is None:  # it never started executing (no plan): nothing to draw
        return []
    r = report.result
    run = RunReport.from_watch(
        report.watch,
        name=report.name,
        status=report.status,
        success=report.success,
        message=report.message,
        started=r.started if r is not None else 0.0,
        finished=r.finished if r is not None else None,
    )
    return write_report(run, folder)


def report_json(report: MissionReport) -> dict[str, Any]:
    r = report.result
    out: dict[str, Any] = {
        "mission": report.name,
        "success": report.success,
        "status": report.status,
        "message": report.message,
        "planning_s": round(report.planning_s, 4),
        "events": report.events_applied,
    }
    if r is not None:
        out |= {
            "plans": len(r.plans),
            "replans": r.replans,
            "actions": len(r.actions),
            "failures": r.failures,
            "total_time_s": round(r.total_time, 3),
            "efficiency_percent": round(r.efficiency_percent, 2),
            "records": [{"action": a.text, **a.to_dict()} for a in r.actions],
        }
    return out
