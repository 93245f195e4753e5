"""``plansys-bridge new-adapter NAME [--dir D]``: scaffold an installable adapter package."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from plansys_bridge.cli.output import say


def register(sub: Any) -> None:
    p = sub.add_parser(
        "new-adapter", help="create an installable adapter package (performer, contract test)"
    )
    p.add_argument("name", help="the performer kind, e.g. gripper")
    p.add_argument("--dir", help="where to create it (default: ./plansys-bridge-NAME)")
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    from plansys_bridge.scaffold import write_adapter

    folder = Path(args.dir or f"plansys-bridge-{args.name.replace('_', '-')}")
    for path in write_adapter(args.name, folder):
        say(f"created {path}")
    say(f"next: pip install -e '{folder}[test]' && pytest {folder}")
    return 0
