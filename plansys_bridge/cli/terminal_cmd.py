"""``plansys-bridge terminal DOMAIN... [--problem P] [--source FILE]``: PlanSys2's terminal.

Loads the (merged) domain and optionally a problem, runs the commands of
``--source`` files, then reads commands from stdin until ``quit`` or end of input.
With stdin not a terminal (a pipe, a file, CI) no prompt is printed, so
``plansys-bridge terminal d.pddl < commands`` gives clean output. Exit status: 0,
or 1 when a command failed in a non-interactive session, 2 for bad input files.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any, TextIO

EXIT_OK = 0
EXIT_COMMAND_FAILED = 1


def register(subparsers: Any) -> None:
    parser = subparsers.add_parser(
        "terminal",
        help="interactive terminal over the knowledge, like plansys2_terminal",
        description=(
            "Open a terminal on the domain made of DOMAIN files (merged as PlanSys2 does). "
            "Commands: get/set/remove instances, predicates, functions, goal; get plan; "
            "run; source FILE; help; quit."
        ),
    )
    parser.add_argument("domains", nargs="+", metavar="DOMAIN", help="domain file(s)")
    parser.add_argument("--problem", metavar="FILE", help="load this problem first")
    parser.add_argument(
        "--source",
        action="append",
        metavar="FILE",
        help="run the commands in FILE before reading stdin (repeatable)",
    )
    parser.add_argument(
        "--solver", action="append", metavar="NAME", help="solver for get plan (repeatable)"
    )
    parser.add_argument("--timeout", type=float, default=30.0, metavar="S", help="planning timeout")
    parser.set_defaults(func=run)


class _ErrorCounter:
    """Wraps the output stream to count error lines the terminal writes."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.errors = 0

    def write(self, text: str) -> int:
        if "error: " in text:
            self.errors += text.count("error: ")
        return self.stream.write(text)

    def flush(self) -> None:
        self.stream.flush()


def run(args: argparse.Namespace, stdin: TextIO | None = None, stdout: TextIO | None = None) -> int:
    from plansys_bridge.knowledge.domain_expert import DomainExpert
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.terminal import Terminal

    inp = stdin if stdin is not None else sys.stdin
    out = _ErrorCounter(stdout if stdout is not None else sys.stdout)
    domain_expert = DomainExpert.from_files(args.domains)
    problem_expert = ProblemExpert(domain_expert)
    if args.problem:
        path = Path(args.problem)
        problem_expert.load_problem(path.read_text(encoding="utf-8"), filename=str(path))

    def planner() -> Any:
        from plansys_bridge.planning.planner import Planner

        return Planner(solvers=args.solver, timeout=args.timeout)

    terminal = Terminal(domain_expert, problem_expert, planner_factory=planner, out=out)  # type: ignore[arg-type]
    for file in args.source or ():
        result = terminal.source(file)
        if result:
            out.write(result + "\n")
    if not terminal.finished:
        terminal.repl(inp)
    interactive = inp.isatty()
    return EXIT_COMMAND_FAILED if out.errors and not interactive else EXIT_OK
