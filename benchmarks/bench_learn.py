"""Planned vs executed makespan before and after learning durations from recordings.

The cooking world of ``plansys_bridge.experiments.timed_cooking``: the domain plans
with duration functions set to the paper's guesses (move 3.8 s, transport 8.8 s,
cook 21 s), while the simulated robots take the world's true times (zones at
different distances, a slow robot2, a quick robot3, cooks at their own pace, every
run varied by 5 %). Steps, all on the virtual clock:

1. ``--train`` missions (seed 1) run with the guesses and are recorded;
2. ``plansys-bridge learn`` (its library calls) estimates every duration function
   the runs observed and writes the functions file;
3. ``--eval`` other missions (seed 2) run three times: with the guesses ("before"),
   with the learned file on top ("after"), and with only the values some run
   observed (``learn --observed-only``: the other guesses stay).

Printed: per phase the median planned makespan (the first plan's), the median
executed makespan, and the median relative error |executed - planned| / executed.

    python benchmarks/bench_learn.py [--train 8] [--eval 8]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from plansys_bridge.experiments.timed_cooking import timed_cooking_mission
from plansys_bridge.learning.outputs import duration_functions, functions_text
from plansys_bridge.learning.runs import known_functions, learn, read_runs
from plansys_bridge.mission import default_missions_dir, run_mission
from plansys_bridge.mission_config import mission_from_dict
from plansys_bridge.pddl.parser import parse_domain_files

DOMAIN = default_missions_dir() / "pddl" / "cooking_timed_domain.pddl"


@dataclass(frozen=True)
class Outcome:
    planned: float
    executed: float
    success: bool

    @property
    def error(self) -> float:
        return abs(self.executed - self.planned) / self.executed if self.executed else 0.0


def run_one(number: int, seed: int, folder: Path, *, record: bool, files: list[str]) -> Outcome:
    data = timed_cooking_mission(number, seed=seed, domain=str(DOMAIN), function_files=files)
    if record:
        data["record"] = str(folder / f"train_{number}")
    mission = mission_from_dict(data, source=f"<mission {number}>", base_dir=folder)
    report = run_mission(mission, out=None)
    result = report.result
    if result is None or not result.plans:
        return Outcome(0.0, 0.0, False)
    return Outcome(result.plans[0].makespan, result.total_time, report.success)


def summary(name: str, outcomes: list[Outcome]) -> str:
    planned = statistics.median(o.planned for o in outcomes)
    executed = statistics.median(o.executed for o in outcomes)
    error = statistics.median(o.error for o in outcomes)
    ok = sum(o.success for o in outcomes)
    return (
        f"{name:<16} planned {planned:7.1f} s   executed {executed:7.1f} s   "
        f"error {100 * error:5.1f} %   ({ok}/{len(outcomes)} succeeded)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--train", type=int, default=8, help="recorded missions to learn from")
    parser.add_argument("--eval", type=int, default=8, help="missions compared before/after")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        t0 = time.perf_counter()
        trained = [run_one(n, 1, folder, record=True, files=[]) for n in range(1, args.train + 1)]
        domain = parse_domain_files([DOMAIN])
        recordings = [folder / f"train_{n}" for n in range(1, args.train + 1)]
        t1 = time.perf_counter()
        runs = read_runs(recordings, domain)
        learned = learn(runs, len(recordings), known_functions(recordings))
        estimates, notes = duration_functions(domain, learned)
        learned_file = folder / "learned.pddl"
        learned_file.write_text(functions_text(estimates, notes, "bench_learn"), encoding="utf-8")
        t2 = time.perf_counter()
        seen_only = folder / "observed.pddl"
        observed_estimates = [e for e in estimates if e.observed]
        seen_only.write_text(functions_text(observed_estimates, notes, "bench_learn"), "utf-8")
        evaluated = range(1, args.eval + 1)
        before = [run_one(n, 2, folder, record=False, files=[]) for n in evaluated]
        after = [run_one(n, 2, folder, record=False, files=[str(learned_file)]) for n in evaluated]
        observed_after = [
            run_one(n, 2, folder, record=False, files=[str(seen_only)]) for n in evaluated
        ]
    observed = sum(e.observed for e in estimates)
    print(
        f"learned {observed} duration values ({len(estimates) - observed} more from their "
        f"action's median) from {len(learned.runs)} action runs "
        f"of {len(recordings)} recorded missions in {t2 - t1:.2f} s "
        f"(recording them took {t1 - t0:.1f} s of wall time)"
    )
    print(summary("training (guess)", trained))
    print(summary("before learning", before))
    print(summary("after learning", after))
    print(summary("observed only", observed_after))
    print("per evaluation mission (planned / executed, s):")
    for n, (b, a) in enumerate(zip(before, after, strict=True), start=1):
        print(
            f"  mission {n}: before {b.planned:6.1f} / {b.executed:6.1f}"
            f"   after {a.planned:6.1f} / {a.executed:6.1f}"
        )


if __name__ == "__main__":
    main()
