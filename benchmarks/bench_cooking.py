"""The paper's Table I, measured: cooking with 1, 2 and 3 robots on the wall clock.

Runs ``plansys-bridge experiment cooking`` for each robot count on the real clock
with every duration scaled by ``--time-scale`` (default 0.05: 20x faster than the
paper, so planning, auction and dispatch overhead weigh 20x more than they did
there), and prints the efficiency next to the paper's figures.

    python benchmarks/bench_cooking.py [--hours 0.25] [--time-scale 0.05]
"""

from __future__ import annotations

import argparse

from plansys_bridge.experiments.cooking import PAPER_EFFICIENCY, CookingConfig, run_cooking


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=0.25, help="mission time per robot count")
    ap.add_argument("--time-scale", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    print(
        f"cooking experiment, wall clock, time scale {args.time_scale} "
        f"({args.hours} h of mission time per row)"
    )
    header = (
        f"{'robots':>6} {'missions':>8} {'plans':>5} {'replans':>7} {'fail':>4} {'dishes':>6} "
        f"{'efficiency':>10} {'paper':>7} {'ratio':>6} {'wall s':>7}"
    )
    print(header)
    for robots in (1, 2, 3):
        s = run_cooking(
            CookingConfig(
                robots=robots,
                hours=args.hours,
                clock="wall",
                time_scale=args.time_scale,
                seed=args.seed,
            )
        )
        paper = PAPER_EFFICIENCY[robots]
        print(
            f"{robots:>6} {s.missions:>8} {s.plans:>5} {s.replans:>7} {s.failures:>4} "
            f"{s.dishes:>6} {s.efficiency_percent:>9.2f}% {paper:>6.2f}% "
            f"{s.efficiency_percent / paper:>6.2f} {s.wall_s:>7.1f}"
        )


if __name__ == "__main__":
    main()
