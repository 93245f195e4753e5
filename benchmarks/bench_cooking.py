"""The paper's Table I, measured over seeds: cooking with 1, 2 and 3 robots.

For each robot count, ``--seeds`` runs of ``plansys-bridge experiment cooking``
(seeds 1..N: which dishes are ordered, when batteries drop) on the chosen clock:
the virtual clock (executor overhead and planning take no mission time: the figure
is what the plans and their scheduling give) or the wall clock with every duration
scaled by ``--time-scale`` (0.05: 20x faster than the paper, so planning, auction
and dispatch overhead weigh 20x more than they did there). Printed per robot
count: the median efficiency, its range, the paper's figure and median / paper, and
the mean wall time spent planning each mission (robots idle meanwhile, so on the wall
clock it is mission time: 50 ms at time scale 0.05 is 1 s of a ~40 s mission).

For every seed below the paper, the bound its dishes allow is printed too: each
mission takes at least max(work / robots, 33.6 s), the work being the summed time
of the actions it executed and 33.6 s the shortest dish (one move, one transport,
one cook); the efficiency at that bound says whether the plan or the world is the
limit. A failed mission is listed with its seed and the reason the run gave.

    python benchmarks/bench_cooking.py [--seeds 8] [--hours 0.25] [--clock virtual|wall]
        [--time-scale 0.05] [--robots 1 2 3]
"""

from __future__ import annotations

import argparse
import statistics
from dataclasses import dataclass, field

from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.experiments.cooking import PAPER_EFFICIENCY, CookingConfig, run_cooking
from plansys_bridge.experiments.cooking_world import PAPER_DURATIONS

SHORTEST_DISH = PAPER_DURATIONS["move"] + PAPER_DURATIONS["transport"] + PAPER_DURATIONS["cook"]


@dataclass
class Seed:
    seed: int
    efficiency: float = 0.0
    missions: int = 0
    replans: int = 0
    failures: int = 0
    failure_reasons: dict[str, int] = field(default_factory=dict)
    planning_s: float = 0.0
    work: list[float] = field(default_factory=list)
    """Summed action time of each mission."""

    def bound_percent(self, robots: int) -> float:
        """Efficiency if every mission took only what its work and dishes require."""
        least = sum(max(w / robots, SHORTEST_DISH) for w in self.work)
        return 100.0 * sum(self.work) / least if least > 0 else 0.0


def run_seed(robots: int, seed: int, args: argparse.Namespace) -> Seed:
    out = Seed(seed)

    def on_plan(_number: int, result: ExecutionResult) -> None:
        out.work.append(sum(a.execution_time for a in result.actions))

    stats = run_cooking(
        CookingConfig(
            robots=robots,
            hours=args.hours,
            clock=args.clock,
            time_scale=args.time_scale if args.clock == "wall" else 1.0,
            seed=seed,
            on_plan=on_plan,
        )
    )
    out.efficiency = stats.efficiency_percent
    out.missions, out.replans, out.failures = stats.missions, stats.replans, stats.failures
    out.planning_s = stats.planning_s
    out.failure_reasons = stats.failure_reasons
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8, help="seeds 1..N per robot count")
    ap.add_argument("--hours", type=float, default=0.25, help="mission time per run")
    ap.add_argument("--clock", choices=("virtual", "wall"), default="virtual")
    ap.add_argument("--time-scale", type=float, default=0.05, help="wall clock only")
    ap.add_argument("--robots", type=int, nargs="+", default=[1, 2, 3])
    args = ap.parse_args()
    scale = f", time scale {args.time_scale}" if args.clock == "wall" else ""
    print(
        f"cooking experiment, {args.clock} clock{scale}, {args.hours} h of mission time per "
        f"run, seeds 1-{args.seeds}"
    )
    print(
        f"{'robots':>6} {'median':>8} {'min':>8} {'max':>8} {'paper':>8} {'ratio':>6} "
        f"{'missions':>8} {'replans':>7} {'fail':>4} {'plan ms':>7}"
    )
    below: list[str] = []
    failed: list[str] = []
    for robots in args.robots:
        seeds = [run_seed(robots, s, args) for s in range(1, args.seeds + 1)]
        effs = [s.efficiency for s in seeds]
        paper = PAPER_EFFICIENCY[robots]
        median = statistics.median(effs)
        missions = sum(s.missions for s in seeds)
        plan_ms = 1000.0 * sum(s.planning_s for s in seeds) / missions if missions else 0.0
        print(
            f"{robots:>6} {median:>7.2f}% {min(effs):>7.2f}% {max(effs):>7.2f}% "
            f"{paper:>7.2f}% {median / paper:>6.2f} {missions:>8} "
            f"{sum(s.replans for s in seeds):>7} {sum(s.failures for s in seeds):>4} "
            f"{plan_ms:>7.1f}"
        )
        for s in seeds:
            if s.efficiency < paper:
                below.append(
                    f"  {robots} robot(s), seed {s.seed}: {s.efficiency:.2f}% "
                    f"(its dishes allow at most {s.bound_percent(robots):.2f}%)"
                )
            failed += [
                f"  {robots} robot(s), seed {s.seed}: {n} x {reason}"
                for reason, n in s.failure_reasons.items()
            ]
    if failed:
        print("failed missions:")
        print("\n".join(failed))
    if below:
        print("seeds below the paper, with the bound their dishes allow:")
        print("\n".join(below))


if __name__ == "__main__":
    main()
