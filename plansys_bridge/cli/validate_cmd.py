"""``plansys-bridge validate DOMAIN... [--problem PROBLEM] [--plan PLAN]``.

Parses the domain files (merged as PlanSys2 merges ``a.pddl:b.pddl``), checks the
problem against the merged domain and, with ``--plan``, checks that the plan runs
and reaches the goal. Prints a one-line summary per input. Exit status: 0 when
everything is valid, 1 when the plan is invalid, 2 for bad input (unreadable
files, PDDL or plan syntax/semantic errors, printed as ``file:line:col``).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.pddl.model import (
    And,
    Condition,
    Domain,
    DurativeAction,
    Problem,
)
from plansys_bridge.textfile import read_text

EXIT_OK = 0
EXIT_INVALID_PLAN = 1
EXIT_BAD_INPUT = 2


def register(subparsers: Any) -> None:
    parser = subparsers.add_parser(
        "validate",
        help="check PDDL domain/problem files (and a plan) and summarise them",
        description=(
            "Parse and merge the DOMAIN files, check PROBLEM against them and, with "
            "--plan, validate the plan. Errors are printed as file:line:col with the "
            "offending text."
        ),
    )
    parser.add_argument("domains", nargs="+", metavar="DOMAIN", help="domain file(s), merged")
    parser.add_argument("--problem", metavar="PROBLEM", help="problem file to check")
    parser.add_argument("--plan", metavar="PLAN", help="plan file to validate (needs --problem)")
    parser.set_defaults(func=run)


def _plural(count: int, word: str) -> str:
    return f"{count} {word}{'' if count == 1 else 's'}"


def domain_summary(domain: Domain) -> str:
    durative = sum(isinstance(a, DurativeAction) for a in domain.actions)
    parts = [
        _plural(len(domain.types), "type"),
        _plural(len(domain.constants), "constant"),
        _plural(len(domain.predicates), "predicate"),
        _plural(len(domain.functions), "function"),
        f"{_plural(len(domain.actions), 'action')} ({durative} durative)",
        _plural(len(domain.derived), "derived predicate"),
    ]
    return f"domain {domain.name}: " + ", ".join(parts)


def _goal_size(goal: Condition) -> int:
    return len(goal.operands) if isinstance(goal, And) else 1


def problem_summary(problem: Problem) -> str:
    parts = [
        _plural(len(problem.objects), "object"),
        _plural(len(problem.init), "fact"),
        _plural(len(problem.init_fluents), "numeric value"),
        _plural(_goal_size(problem.goal), "goal condition"),
    ]
    if problem.metric is not None:
        parts.append(f"metric {problem.metric.direction}")
    return f"problem {problem.name}: " + ", ".join(parts)


def run(args: argparse.Namespace) -> int:
    from plansys_bridge.pddl.parser import parse_domain_files, parse_problem

    if args.plan and not args.problem:
        print("error: --plan needs --problem", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        domain = parse_domain_files(args.domains)
        print(domain_summary(domain))
        if not args.problem:
            return EXIT_OK
        problem = parse_problem(read_text(args.problem, "problem file"), domain, args.problem)
        print(problem_summary(problem))
        if not args.plan:
            return EXIT_OK
        from plansys_bridge.planning.plan import parse_plan
        from plansys_bridge.planning.validation import validate_plan

        plan = parse_plan(read_text(args.plan, "plan file"), args.plan)
        report = validate_plan(domain, problem, plan)
    except PlansysBridgeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if report.valid:
        print(report.message)
        return EXIT_OK
    print(f"error: {args.plan}: {report.message}", file=sys.stderr)
    return EXIT_INVALID_PLAN
