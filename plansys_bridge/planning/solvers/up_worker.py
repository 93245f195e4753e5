"""Run one unified-planning engine on a PDDL pair and print the plan (a child process).

Several unified-planning engines plan inside the Python process and cannot be
interrupted; running them in a child started by :mod:`.process` gives them the
same hard timeout as any external solver. Output: plan lines in PlanSys2's format
on stdout; exit status 0 solved, 10 unsolvable, 11 timeout, 13 unsupported,
2 bad input, 1 anything else (with the reason on stderr).

Usage: ``python -m plansys_bridge.planning.solvers.up_worker [--engine NAME]
[--timeout S] DOMAIN PROBLEM``
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

EXIT_SOLVED = 0
EXIT_ERROR = 1
EXIT_BAD_INPUT = 2
EXIT_UNSOLVABLE = 10
EXIT_TIMEOUT = 11
EXIT_UNSUPPORTED = 13


def _object_name(param: Any) -> str:
    return str(param.object().name if param.is_object_exp() else param)


def _lines(plan: Any) -> list[str]:
    """PlanSys2 plan lines from a unified-planning time-triggered or sequential plan."""
    lines = []
    if hasattr(plan, "timed_actions"):
        for start, inst, duration in plan.timed_actions:
            args = " ".join(_object_name(p) for p in inst.actual_parameters)
            text = f"({inst.action.name} {args})" if args else f"({inst.action.name})"
            dur = float(duration) if duration is not None else 0.0
            lines.append(f"{float(start):.6f}: {text}  [{dur:.6f}]")
    else:
        for index, inst in enumerate(plan.actions):
            args = " ".join(_object_name(p) for p in inst.actual_parameters)
            text = f"({inst.action.name} {args})" if args else f"({inst.action.name})"
            lines.append(f"{float(index):.6f}: {text}  [0.000000]")
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="up_worker")
    parser.add_argument("--engine", default=None)
    parser.add_argument("--timeout", type=float, default=None)
    parser.add_argument("domain")
    parser.add_argument("problem")
    args = parser.parse_args(argv)
    try:
        from unified_planning.engines import PlanGenerationResultStatus as Status
        from unified_planning.io import PDDLReader
        from unified_planning.shortcuts import OneshotPlanner, get_environment
    except ImportError as exc:
        print(f"unified-planning is not installed: {exc}", file=sys.stderr)
        return EXIT_UNSUPPORTED
    env = get_environment()
    env.credits_stream = None
    try:
        problem = PDDLReader(env).parse_problem(args.domain, args.problem)
    except Exception as exc:  # the reader raises many types; the message is what matters
        print(f"unified-planning cannot read the task: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        if args.engine:
            planner = OneshotPlanner(name=args.engine)
            if not planner.supports(problem.kind):
                print(f"engine {args.engine} does not support this problem kind", file=sys.stderr)
                return EXIT_UNSUPPORTED
        else:
            planner = OneshotPlanner(problem_kind=problem.kind)
    except Exception as exc:
        print(f"no unified-planning engine for this task: {exc}", file=sys.stderr)
        return EXIT_UNSUPPORTED
    try:
        with planner:
            result = planner.solve(problem, timeout=args.timeout)
    except Exception as exc:  # engines raise their own types; say which engine and why
        print(f"engine {planner.name} failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_ERROR
    print(f"; engine {planner.name}; status {result.status.name}", file=sys.stderr)
    if result.status in (Status.SOLVED_SATISFICING, Status.SOLVED_OPTIMALLY) and result.plan:
        print("\n".join(_lines(result.plan)))
        return EXIT_SOLVED
    for log in result.log_messages or ():
        print(f"; {log.message}", file=sys.stderr)
    if result.status in (Status.UNSOLVABLE_PROVEN, Status.UNSOLVABLE_INCOMPLETELY):
        return EXIT_UNSOLVABLE
    if result.status is Status.TIMEOUT:
        return EXIT_TIMEOUT
    if result.status is Status.UNSUPPORTED_PROBLEM:
        return EXIT_UNSUPPORTED
    return EXIT_ERROR


if __name__ == "__main__":
    raise SystemExit(main())
