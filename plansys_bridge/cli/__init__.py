"""The ``plansys-bridge`` command line.

Each subcommand lives in its own module exposing ``register(subparsers)``; the
module is imported only when listed here, so a missing optional dependency of one
command never breaks the others.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from plansys_bridge import __version__
from plansys_bridge.cli.signals import sigterm_interrupts
from plansys_bridge.cli.verbosity import add_verbosity, configure_logging
from plansys_bridge.errors import PlansysBridgeError

SUBCOMMANDS = (
    "validate",
    "plan",
    "run",
    "experiment",
    "terminal",
    "demo",
    "performers",
    "bridge",
    "report",
    "learn",
    "monitor",
    "serve",
    "new-adapter",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="plansys-bridge",
        description="Plan and execute robot missions the PlanSys2 way.",
    )
    parser.add_argument("--version", action="version", version=f"plansys-bridge {__version__}")
    # also before the command (``plansys-bridge -v run M.yaml``); merged in main()
    top = parser.add_mutually_exclusive_group()
    top.add_argument(
        "-v", "--verbose", dest="top_verbose", action="count", default=0, help=argparse.SUPPRESS
    )
    top.add_argument("-q", "--quiet", dest="top_quiet", action="store_true", help=argparse.SUPPRESS)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMANDS:
        module = importlib.import_module(f"plansys_bridge.cli.{name.replace('-', '_')}_cmd")
        module.register(sub)
    for command in sub.choices.values():
        add_verbosity(command)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.verbose = max(int(getattr(args, "verbose", 0) or 0), args.top_verbose)
    args.quiet = bool(getattr(args, "quiet", False) or args.top_quiet)
    if args.verbose and args.quiet:
        parser.error("-v/--verbose and -q/--quiet exclude each other")
    configure_logging(args)
    with sigterm_interrupts() as termination:
        try:
            code: int = args.func(args)
        except PlansysBridgeError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            print("terminated" if termination.received else "interrupted", file=sys.stderr)
            return 143 if termination.received else 130
        except BrokenPipeError:  # the reader of stdout left (| head): end quietly, as Unix does
            from plansys_bridge.cli.output import drop_stdout

            drop_stdout()
            return 141
    return code


if __name__ == "__main__":
    raise SystemExit(main())
