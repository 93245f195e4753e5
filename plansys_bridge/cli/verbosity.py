"""``-v/--verbose`` and ``-q/--quiet`` on every subcommand, and the log format they set.

Every command takes them the same way, so a newcomer never has to learn which
command is chatty: ``-q`` shows errors only (and, for missions, only the summary),
``-v`` adds the project's INFO messages (replans, auction winners, performers
joining), ``-vv`` everything down to DEBUG. Log lines carry a wall-clock timestamp
with milliseconds, since they are read next to a robot's own logs.
"""

from __future__ import annotations

import argparse
import logging

__all__ = ["LOG_FORMAT", "add_verbosity", "configure_logging"]

LOG_FORMAT = "%(asctime)s.%(msecs)03d %(levelname)-7s %(name)s: %(message)s"


def add_verbosity(parser: argparse.ArgumentParser) -> None:
    """Add ``-v`` (repeatable) and ``-q`` to ``parser`` unless it already has them."""
    if any("-v" in action.option_strings for action in parser._actions):
        return
    group = parser.add_mutually_exclusive_group()
    group.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="log more (-v: info, -vv: debug), with timestamps",
    )
    group.add_argument("-q", "--quiet", action="store_true", help="print only results and errors")


def log_level(args: argparse.Namespace) -> int:
    if getattr(args, "quiet", False):
        return logging.ERROR
    verbose = int(getattr(args, "verbose", 0) or 0)
    return logging.DEBUG if verbose >= 2 else logging.INFO if verbose == 1 else logging.WARNING


def configure_logging(args: argparse.Namespace) -> None:
    """Set the root logger from ``args`` (replacing any handler set before)."""
    logging.basicConfig(
        level=log_level(args), format=LOG_FORMAT, datefmt="%Y-%m-%d %H:%M:%S", force=True
    )
