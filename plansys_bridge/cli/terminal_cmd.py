"""``plansys-bridge terminal DOMAIN... [--problem P] [--source FILE] [--mission M]``.

PlanSys2's terminal. Loads the (merged) domain and optionally a problem, runs the
commands of ``--source`` files, then reads commands from stdin until ``quit`` or
end of input. With ``--mission M.yaml`` the domain, the initial knowledge and the
performers come from a mission file, and ``run`` executes plans with those
performers (each ``run`` starts them, executes with live progress, and stops them;
the mission's timed events are not replayed), and ``check actors`` lists the
performers alive on the mission's hub from their heartbeats (over DDS, those of
other processes too). ``--no-performers``: the mission's performers are served by
``plansys-bridge performers`` in other processes over DDS. Progress is a live table
on a terminal, one line per change otherwise. Without a mission the terminal plans
but does not run.
With stdin not a terminal (a pipe, a file, CI) no prompt is printed, so
``plansys-bridge terminal d.pddl < commands`` gives clean output. Exit status: 0,
or 1 when a command failed in a non-interactive session, 2 for bad input files.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TextIO

from plansys_bridge.cli.options import check_positive
from plansys_bridge.textfile import TextFileError, read_text

if TYPE_CHECKING:
    from plansys_bridge.terminal.mission_runner import MissionRunner

EXIT_OK = 0
EXIT_COMMAND_FAILED = 1
EXIT_BAD_INPUT = 2


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
    parser.add_argument("domains", nargs="*", metavar="DOMAIN", help="domain file(s)")
    parser.add_argument(
        "--mission", metavar="YAML", help="take domain, knowledge and performers from a mission"
    )
    parser.add_argument(
        "--no-performers",
        action="store_true",
        help="with --mission: the performers run in other processes "
        "(`plansys-bridge performers`, needs transport: {kind: dds})",
    )
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


def _line_writer(out: _ErrorCounter) -> Callable[[str], None]:
    def write(line: str) -> None:
        out.write(line + "\n")
        out.flush()

    return write


def _console(stream: TextIO) -> Any:
    """A rich console drawing on ``stream`` (None without rich: plain lines then)."""
    try:
        from rich.console import Console
    except ImportError:
        return None
    return Console(file=stream, force_terminal=True)


def run(args: argparse.Namespace, stdin: TextIO | None = None, stdout: TextIO | None = None) -> int:
    from plansys_bridge.knowledge.domain_expert import DomainExpert
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.terminal import Terminal
    from plansys_bridge.terminal.mission_runner import MissionRunner

    check_positive(args.timeout, "--timeout")
    inp = stdin if stdin is not None else sys.stdin
    out = _ErrorCounter(stdout if stdout is not None else sys.stdout)
    if bool(args.domains) == bool(args.mission):
        print("error: give either DOMAIN file(s) or --mission", file=sys.stderr)
        return EXIT_BAD_INPUT

    def planner() -> Any:
        from plansys_bridge.planning.planner import Planner

        return Planner(solvers=args.solver, timeout=args.timeout)

    runner: MissionRunner | None = None
    if args.mission:
        from plansys_bridge.mission import build_knowledge
        from plansys_bridge.mission_config import load_mission

        mission = load_mission(args.mission)
        problem_expert = build_knowledge(
            mission, DomainExpert.from_files(list(mission.domain_paths)).domain
        )
        domain_expert = problem_expert.domain_expert
        stream = stdout if stdout is not None else sys.stdout
        runner = MissionRunner(
            mission,
            problem_expert,
            planner,
            out=_line_writer(out),
            local_performers=not args.no_performers,
            live=stream.isatty(),
            console=_console(stdout) if stdout is not None and stream.isatty() else None,
        )
    elif args.no_performers:
        print("error: --no-performers needs --mission", file=sys.stderr)
        return EXIT_BAD_INPUT
    else:
        domain_expert = DomainExpert.from_files(args.domains)
        problem_expert = ProblemExpert(domain_expert)
    if args.problem:
        try:
            text = read_text(args.problem, "problem file")
        except TextFileError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        problem_expert.load_problem(text, filename=args.problem)

    terminal = Terminal(
        domain_expert,
        problem_expert,
        planner_factory=planner,
        runner=runner,
        out=out,  # type: ignore[arg-type]
    )
    terminal.stream_source = True
    for file in args.source or ():
        try:
            result = terminal.source(file)
        except TextFileError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if result:
            out.write(result + "\n")
    if not terminal.finished:
        terminal.repl(inp)
    interactive = inp.isatty()
    return EXIT_COMMAND_FAILED if out.errors and not interactive else EXIT_OK
