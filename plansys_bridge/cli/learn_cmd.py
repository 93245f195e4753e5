"""``plansys-bridge learn RECORDING... --domain D``: action durations and success rates
learned from recorded missions.

Prints, per action and per ground action, how many runs succeeded, the median
duration with its spread (interquartile range, standard deviation) and the success
rate; ``--functions`` writes the medians as duration-function values for the
planner, ``--costs`` the expected cost per performer for best-bid auctions,
``--json`` everything as JSON.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from plansys_bridge.cli.output import say


def register(sub: Any) -> None:
    p = sub.add_parser(
        "learn",
        help="learn action durations and success rates from recorded missions",
    )
    p.add_argument("recordings", nargs="+", metavar="RECORDING", help="bags written by --record")
    p.add_argument(
        "--domain",
        required=True,
        action="append",
        metavar="D",
        help="the missions' domain file (repeat for a domain in several files)",
    )
    p.add_argument(
        "--functions",
        metavar="FILE",
        help="write duration-function values (PDDL init entries) for knowledge.function_files",
    )
    p.add_argument(
        "--costs", metavar="FILE", help="write per-performer bid costs (YAML) for bid_costs:"
    )
    p.add_argument(
        "--observed-only",
        action="store_true",
        help="write only the functions some run observed (default: the others the "
        "missions knew get their action's median)",
    )
    p.add_argument("--json", action="store_true", help="print the statistics as JSON")
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    from plansys_bridge.learning.outputs import (
        bid_costs,
        bid_costs_text,
        duration_functions,
        functions_text,
    )
    from plansys_bridge.learning.runs import known_functions, learn, read_runs
    from plansys_bridge.pddl.parser import parse_domain_files

    domain = parse_domain_files(args.domain)
    runs = read_runs(args.recordings, domain)
    learned = learn(runs, len(args.recordings), known_functions(args.recordings))
    estimates, notes = duration_functions(domain, learned, fill=not args.observed_only)
    header = (
        f"learned by plansys-bridge learn from {learned.recordings} recording(s), "
        f"{len(learned.runs)} action runs\n" + "\n".join(str(r) for r in args.recordings)
    )
    written = []
    if args.functions:
        _write(args.functions, functions_text(estimates, notes, header))
        observed = sum(e.observed for e in estimates)
        written.append(
            f"wrote {len(estimates)} duration values ({observed} observed) to {args.functions}"
        )
    if args.costs:
        _write(args.costs, bid_costs_text(learned, header))
        written.append(f"wrote bid costs of {len(bid_costs(learned))} performers to {args.costs}")
    if args.json:
        say(json.dumps(_as_json(learned, estimates, notes), indent=2))
    else:
        say(_table(learned))
        for note in notes:
            say(f"note: {note}")
    if not args.quiet:
        for line in written:
            say(line)
    return 0


def _write(path: str, text: str) -> None:
    from plansys_bridge.learning.runs import LearnError

    try:
        Path(path).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise LearnError(f"{path}: cannot write: {exc.strerror or exc}") from exc


def _table(learned: Any) -> str:
    rows: list[tuple[str, ...]] = [("action", "runs", "median s", "IQR", "stdev", "success")]
    by_ground = learned.by_ground()
    for action, stats in learned.by_action().items():
        rows.append((action, *_cells(stats)))
        for (name, arguments), g in by_ground.items():
            if name == action:
                rows.append(("  (" + " ".join((name, *arguments)) + ")", *_cells(g)))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = [
        "  ".join(
            c.ljust(w) if i == 0 else c.rjust(w)
            for i, (c, w) in enumerate(zip(r, widths, strict=True))
        )
        for r in rows
    ]
    head = f"{len(learned.runs)} action runs from {learned.recordings} recording(s)"
    return "\n".join([head, *lines])


def _cells(stats: Any) -> tuple[str, ...]:
    if not stats.count:
        return (f"0/{stats.attempts}", "-", "-", "-", "0%")
    return (
        f"{stats.count}/{stats.attempts}",
        f"{stats.median:.3f}",
        f"{stats.iqr:.3f}",
        f"{stats.stdev:.3f}",
        f"{stats.success_rate:.0%}",
    )


def _as_json(learned: Any, estimates: list[Any], notes: list[str]) -> dict[str, Any]:
    return {
        "recordings": learned.recordings,
        "runs": len(learned.runs),
        "actions": {a: s.to_dict() for a, s in learned.by_action().items()},
        "ground_actions": {
            "(" + " ".join((a, *args)) + ")": s.to_dict()
            for (a, args), s in learned.by_ground().items()
        },
        "performers": {
            f"{p} {a}": s.to_dict() for (p, a), s in learned.by_performer().items() if p
        },
        "duration_functions": {
            e.fluent: e.stats.to_dict() | {"observed": e.observed} for e in estimates
        },
        "notes": notes,
    }
