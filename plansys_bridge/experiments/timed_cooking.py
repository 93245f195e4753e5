"""The cooking world with true durations that differ from the domain's guesses.

The domain (``configs/pddl/cooking_timed_domain.pddl``) plans with duration
functions; a mission starts from the paper's guesses for all of them, while its
simulated performers take the world's true times: some zones are further apart
than others, robot2 is slow, robot3 quick, each cook has its own pace, and every
run varies by a few percent. Learning from recorded runs of this world should
bring the planned makespan close to the executed one (``benchmarks/bench_learn.py``
and the learning tests use it).
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from typing import Any

from plansys_bridge.experiments.cooking_world import (
    ZONES,
    dish_order,
    robot_names,
    world_setup,
)

__all__ = ["GUESSES", "guess_functions", "timed_cooking_mission", "true_duration"]

GUESSES = {"move": 3.8, "transport": 8.8, "recharge": 10.0, "cook": 21.0}
"""The paper's durations: what the domain is told before anything is learned."""

ROBOT_PACE = {"robot1": 1.0, "robot2": 1.5, "robot3": 0.8}
COOK_TIME = {"robot1": 18.0, "robot2": 27.0, "robot3": 22.0}
ZONE_PLACE = {
    "cooking_zone": 0.0,
    "fridge_zone": 1.0,
    "pantry_zone": 3.0,
    "watertap_zone": 1.5,
    "recharge_zone": 2.0,
}
"""Where zones are along one corridor (units of the paper's move)."""


def true_duration(action: str, args: Sequence[str], jitter: float = 1.0) -> float:
    """The world's time for one ground action (``jitter`` scales one run)."""
    robot = args[0]
    pace = ROBOT_PACE.get(robot, 1.0)
    if action.startswith("cook_"):
        return round(COOK_TIME.get(robot, GUESSES["cook"]) * jitter, 3)
    if action == "recharge":
        return round(GUESSES["recharge"] * jitter, 3)
    z1, z2 = args[-2], args[-1]
    legs = max(0.5, abs(ZONE_PLACE[z1] - ZONE_PLACE[z2]))
    base = 2.5 if action == "move" else 6.0
    return round(base * legs * pace * jitter, 3)


def guess_functions(robots: Sequence[str]) -> list[str]:
    """Every duration-function value of the domain, set to the paper's guesses."""
    out = []
    for r in robots:
        for z1 in ZONES:
            for z2 in ZONES:
                out.append(f"(= (move_time {r} {z1} {z2}) {GUESSES['move']})")
                out.append(f"(= (transport_time {r} {z1} {z2}) {GUESSES['transport']})")
        out.append(f"(= (recharge_time {r}) {GUESSES['recharge']})")
        out.append(f"(= (cook_time {r}) {GUESSES['cook']})")
    return out


def _performers(
    robots: Sequence[str], ingredients: Sequence[str], rng: random.Random, spread: float
) -> list[dict[str, Any]]:
    def jitter() -> float:
        return max(0.5, rng.gauss(1.0, spread))

    entries: list[dict[str, Any]] = []
    for r in robots:
        base: dict[str, float] = {f"(recharge {r} recharge_zone)": true_duration("recharge", [r])}
        for z1 in ZONES:
            for z2 in ZONES:
                base[f"(move {r} {z1} {z2})"] = true_duration("move", [r, z1, z2], jitter())
                for ing in ingredients:
                    t = true_duration("transport", [r, ing, z1, z2], jitter())
                    base[f"(transport {r} {ing} {z1} {z2})"] = t
        cook = true_duration("cook_cake", [r], jitter())
        entries.append(
            {
                "kind": "simulated",
                "name": f"{r}_base",
                "actions": {"move": [r], "transport": [r], "recharge": [r]},
                "durations": base,
            }
        )
        entries.append(
            {
                "kind": "simulated",
                "name": f"{r}_arm",
                "actions": {a: [r] for a in ("cook_omelette", "cook_cake", "cook_spaghetti")},
                "durations": {a: cook for a in ("cook_omelette", "cook_cake", "cook_spaghetti")},
            }
        )
    return entries


def timed_cooking_mission(
    number: int,
    *,
    robots: int = 3,
    seed: int = 0,
    spread: float = 0.05,
    function_files: Sequence[str] = (),
    domain: str,
) -> dict[str, Any]:
    """A mission file's content: two random dishes (order ``number`` of ``seed``),
    the guesses for every duration (then ``function_files`` on top), and simulated
    performers taking the true times, each varied by ``spread`` (relative)."""
    rng = random.Random(seed * 1000 + number)
    names = robot_names(robots)
    setup = world_setup(robots)
    order = dish_order(number, rng, robots=names)
    ingredients = [n for n, t in order.instances.items() if t == "ingredient"]
    performers = _performers(names, ingredients, rng, spread)
    knowledge: dict[str, Any] = {
        "instances": setup.instances | order.instances,
        "predicates": setup.predicates + order.predicates,
        "functions": guess_functions(names),
    }
    if function_files:
        knowledge["function_files"] = list(function_files)
    return {
        "name": f"timed_cooking_{seed}_{number}",
        "domain": domain,
        "knowledge": knowledge,
        "goal": order.goal,
        "performers": performers,
        "clock": {"kind": "virtual"},
    }
