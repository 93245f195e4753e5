"""``plansys-bridge plan DOMAIN... PROBLEM``: plan, validate, print the plan.

The plan goes to stdout in PlanSys2's format (``0.000: (move r1 a b)  [5.000]``)
followed by comment lines with the makespan, the solver and the verdict, so the
output is itself a plan file. Exit status: 0 with a valid plan, 1 when no plan
was found (unsolvable, timeout, no solver fits, solver error) or the plan is
invalid, 2 for bad input (unreadable or wrong PDDL, bad options).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from plansys_bridge.cli.options import check_at_least, check_non_negative
from plansys_bridge.errors import ConfigError
from plansys_bridge.textfile import TextFileError, read_text

EXIT_OK = 0
EXIT_NO_PLAN = 1
EXIT_BAD_INPUT = 2


def register(subparsers: Any) -> None:
    parser = subparsers.add_parser(
        "plan",
        help="plan a problem and print the plan in PlanSys2's format",
        description=(
            "Plan PROBLEM in the domain made of DOMAIN files (merged as PlanSys2 does). "
            "Solvers are tried in the order given by --solver (default: kairos first, "
            "then PlanSys2's solvers when installed); the first that supports the task is used."
        ),
    )
    parser.add_argument("files", nargs="*", metavar="FILE", help="DOMAIN... PROBLEM")
    parser.add_argument(
        "--solver",
        action="append",
        metavar="NAME",
        help="solver to use; repeat for an order of preference (see --list-solvers)",
    )
    parser.add_argument("--timeout", type=float, default=30.0, metavar="S", help="seconds")
    parser.add_argument("-o", "--output", metavar="FILE", help="write the plan to FILE")
    parser.add_argument(
        "--improve",
        type=float,
        metavar="S",
        help="keep searching for a shorter plan for S seconds (Kairos anytime mode)",
    )
    parser.add_argument("--threads", type=int, metavar="N", help="solver threads (Kairos)")
    parser.add_argument(
        "--fallback", action="store_true", help="on a solver error or timeout try the next one"
    )
    parser.add_argument(
        "--reschedule",
        action="store_true",
        help="move every action as early as its dependencies allow; print makespans",
    )
    parser.add_argument(
        "--no-validate", action="store_true", help="do not check the plan before printing it"
    )
    parser.add_argument(
        "--eliminate",
        action="store_true",
        help="drop the steps nothing needs (greedy action elimination, re-validated)",
    )
    parser.add_argument(
        "--list-solvers", action="store_true", help="list solvers, availability and features"
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.list_solvers:
        return _list_solvers()
    if len(args.files) < 2:
        print("error: give at least one DOMAIN file and one PROBLEM file", file=sys.stderr)
        return EXIT_BAD_INPUT
    from plansys_bridge.pddl.parser import parse_domain_files, parse_problem
    from plansys_bridge.planning.planner import Planner

    *domain_files, problem_file = args.files
    domain = parse_domain_files(domain_files)
    try:
        problem_text = read_text(problem_file, "problem file")
    except TextFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    problem = parse_problem(problem_text, domain, problem_file)

    options: dict[str, Any] = {}
    if args.improve is not None:
        options["improve_for"] = args.improve
    if args.threads is not None:
        options["threads"] = args.threads
    try:
        check_non_negative(args.improve, "--improve")
        check_at_least(args.threads, 1, "--threads")
        planner = Planner(
            args.solver,
            timeout=args.timeout,
            options=options,
            fallback=args.fallback,
            validate=not args.no_validate,
            eliminate=args.eliminate,
        )
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    result = planner.solve(domain, problem)
    if not result.solved or result.plan is None:
        print(
            f"error: no plan ({result.status.value}) from {result.solver} "
            f"after {result.elapsed_s:.2f} s: {result.message}",
            file=sys.stderr,
        )
        if result.validation is not None and result.plan is not None:
            sys.stderr.write("the invalid plan:\n" + result.plan.to_text(_precision(result.plan)))
        return EXIT_NO_PLAN
    plan = result.plan
    notes = [f"; solver {result.solver}, {result.elapsed_s:.3f} s, {len(plan)} steps"]
    if result.validation is not None:
        notes.append(f"; {result.validation.message}")
    if args.reschedule:
        # only here: the plan graph brings networkx, a third of a plain run's start-up
        from plansys_bridge.planning.schedule import reschedule_report

        rescheduled = reschedule_report(plan, domain, problem)
        plan = rescheduled.plan
        notes.append(
            f"; rescheduled: makespan before {rescheduled.makespan_before:.3f}, "
            f"after {rescheduled.makespan_after:.3f} ({rescheduled.message})"
        )
    notes.append(f"; makespan {plan.makespan:.3f}")
    text = plan.to_text(_precision(plan))
    if args.output:
        try:
            Path(args.output).write_text(text, encoding="utf-8")
        except OSError as exc:
            print(f"error: cannot write {args.output}: {exc.strerror}", file=sys.stderr)
            return EXIT_BAD_INPUT
        notes.insert(0, f"; plan written to {args.output}")
    else:
        sys.stdout.write(text)
    print("\n".join(notes))
    return EXIT_OK


def _precision(plan: Any) -> int:
    """Three decimals unless the plan's times need more (LPG-td separates by 0.00025)."""
    for digits in (3, 4, 6):
        scale = 10**digits
        if all(
            abs(v * scale - round(v * scale)) < 1e-6 * scale
            for s in plan.steps
            for v in (s.time, s.duration)
        ):
            return digits
    return 6


def _list_solvers() -> int:
    from plansys_bridge.errors import PluginError
    from plansys_bridge.planning.capabilities import describe
    from plansys_bridge.planning.solvers import load_solver, solver_names

    for name in solver_names():
        try:
            cls = load_solver(name)
        except PluginError as exc:
            print(f"{name:18} broken: {exc}")
            continue
        reason = cls.unavailable_reason()
        state = "available" if reason is None else f"unavailable: {reason}"
        print(f"{name:18} {state}\n{'':18} features: {describe(cls.capabilities)}")
    return EXIT_OK
