"""`validate` and `plan` as whole processes, against the peers a user would run instead.

* ``plansys-bridge validate DOMAIN --problem PROBLEM`` on a large classical problem
  (a corridor of N rooms, several hundred KB) against a process that parses the same
  two files with the ``pddl`` library (``pddl.parse_domain`` / ``parse_problem``);
* ``plansys-bridge plan DOMAIN PROBLEM`` on the 12-dish kitchen with 3 robots against
  ``kairos solve DOMAIN PROBLEM --no-anytime --threads 1`` (Kairos' own command line,
  the solver ``plan`` embeds).

Each is the CPU time (user + system) of the finished child, median of ``--runs``
runs taken in turn with its peer, and the ratio ours / peer. Files are written to a
temporary directory.

Run: ``python benchmarks/bench_cli_process.py [--runs 5] [--rooms 4000]``
"""

from __future__ import annotations

import argparse
import itertools
import random
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from plansys_bridge.experiments.cooking_world import cooking_domain_path, dish_order, world_setup

CORRIDOR = """(define (domain corridor)
  (:requirements :strips :typing)
  (:types robot room)
  (:predicates (at ?r - robot ?x - room) (connected ?a ?b - room) (visited ?x - room))
  (:action go
    :parameters (?r - robot ?a ?b - room)
    :precondition (and (at ?r ?a) (connected ?a ?b))
    :effect (and (not (at ?r ?a)) (at ?r ?b) (visited ?b))))
"""

PDDL_PEER = (
    "import sys\n"
    "from pddl import parse_domain, parse_problem\n"
    "parse_domain(sys.argv[1])\n"
    "parse_problem(sys.argv[2])\n"
)


def corridor_problem(rooms: int) -> str:
    names = [f"room{i}" for i in range(rooms)]
    links = " ".join(
        f"(connected {a} {b}) (connected {b} {a})" for a, b in itertools.pairwise(names)
    )
    return (
        "(define (problem corridor_long) (:domain corridor)\n"
        f"  (:objects r1 - robot {' '.join(names)} - room)\n"
        f"  (:init (at r1 room0) {links})\n"
        f"  (:goal (and (visited {names[-1]}))))\n"
    )


def kitchen_problem(robots: int, dishes: int) -> str:
    setup = world_setup(robots)
    order = dish_order(1, random.Random(7), dishes=dishes)
    instances = {**setup.instances, **order.instances}
    objects = "\n".join(f"    {name} - {kind}" for name, kind in instances.items())
    init = "\n".join(f"    {fact}" for fact in setup.predicates + order.predicates)
    return (
        f"(define (problem kitchen) (:domain cooking)\n"
        f"  (:objects\n{objects})\n  (:init\n{init})\n  (:goal {order.goal}))\n"
    )


def cpu_of(command: list[str]) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()[-300:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def paired(ours: list[str], peer: list[str], runs: int) -> tuple[float, float]:
    cpu_of(ours)
    cpu_of(peer)
    mine, theirs = [], []
    for _ in range(runs):
        mine.append(cpu_of(ours))
        theirs.append(cpu_of(peer))
    return statistics.median(mine), statistics.median(theirs)


def tool(name: str) -> str:
    found = shutil.which(name, path=str(Path(sys.executable).parent)) or shutil.which(name)
    if found is None:
        raise SystemExit(f"{name} not found next to {sys.executable} nor on PATH")
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--rooms", type=int, default=4000)
    args = parser.parse_args()
    bridge = tool("plansys-bridge")
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        (d / "corridor.pddl").write_text(CORRIDOR)
        (d / "long.pddl").write_text(corridor_problem(args.rooms))
        (d / "kitchen.pddl").write_text(kitchen_problem(3, 12))
        size = (d / "long.pddl").stat().st_size / 1024
        rows = []
        try:
            import pddl  # noqa: F401
        except ImportError:
            rows.append(("validate", "the pddl package is not installed", 0.0, 0.0))
        else:
            rows.append(
                (
                    f"validate ({size:.0f} KB classical problem)",
                    "pddl library",
                    *paired(
                        [
                            bridge,
                            "validate",
                            str(d / "corridor.pddl"),
                            "--problem",
                            str(d / "long.pddl"),
                            "-q",
                        ],
                        [
                            sys.executable,
                            "-c",
                            PDDL_PEER,
                            str(d / "corridor.pddl"),
                            str(d / "long.pddl"),
                        ],
                        args.runs,
                    ),
                )
            )
        domain = str(cooking_domain_path())
        rows.append(
            (
                "plan (3 robots, 12 dishes)",
                "kairos solve",
                *paired(
                    [bridge, "plan", domain, str(d / "kitchen.pddl"), "-q"],
                    [
                        tool("kairos"),
                        "solve",
                        domain,
                        str(d / "kitchen.pddl"),
                        "--no-anytime",
                        "--threads",
                        "1",
                    ],
                    args.runs,
                ),
            )
        )
    print(f"Whole-process CPU time, median of {args.runs} runs taken in turn with the peer")
    print(f"{'command':<38} {'peer':<14} {'ms':>8} {'peer ms':>8} {'ratio':>6}")
    for what, peer, mine, theirs in rows:
        if not theirs:
            print(f"{what:<38} {peer}")
            continue
        print(
            f"{what:<38} {peer:<14} {mine * 1e3:>8.0f} {theirs * 1e3:>8.0f} {mine / theirs:>6.2f}"
        )


if __name__ == "__main__":
    main()
