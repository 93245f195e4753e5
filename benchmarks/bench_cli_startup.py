"""Start-up of the command line as whole processes, against a bare Python start.

For ``plansys-bridge --help`` and ``plansys-bridge COMMAND --help`` of every command,
the CPU time (user + system, from the operating system's accounting of the finished
child) of the whole process, run in turn with the peer ``python -c pass`` (A B A B
...), after one warm-up of each. Printed: the medians and the median of the
per-pair ratios (a ratio taken pair by pair holds when the machine's speed drifts).

Run: ``python benchmarks/bench_cli_startup.py [--runs 7] [--json]``
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
from typing import Any

from plansys_bridge.cli import SUBCOMMANDS

PEER = [sys.executable, "-c", "pass"]


def cpu_of(command: list[str]) -> float:
    """CPU seconds (user + system) the finished child process used."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def paired(command: list[str], runs: int) -> dict[str, float]:
    cpu_of(command)
    cpu_of(PEER)
    mine: list[float] = []
    peer: list[float] = []
    for _ in range(runs):
        mine.append(cpu_of(command))
        peer.append(cpu_of(PEER))
    ratios = [m / p for m, p in zip(mine, peer, strict=True) if p > 0]
    return {
        "cpu_ms": statistics.median(mine) * 1e3,
        "peer_cpu_ms": statistics.median(peer) * 1e3,
        "ratio": statistics.median(ratios) if ratios else float("nan"),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    tool = [sys.executable, "-m", "plansys_bridge"]
    rows: dict[str, Any] = {}
    for argv in (["--help"], *([name, "--help"] for name in SUBCOMMANDS)):
        rows["plansys-bridge " + " ".join(argv)] = paired(tool + argv, args.runs)
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    print(f"Whole-process CPU time, median of {args.runs} runs; peer: python -c pass")
    print(f"{'command':<36} {'ms':>8} {'peer ms':>8} {'ratio':>7}")
    for name, r in rows.items():
        print(f"{name:<36} {r['cpu_ms']:>8.1f} {r['peer_cpu_ms']:>8.1f} {r['ratio']:>7.2f}")


if __name__ == "__main__":
    main()
