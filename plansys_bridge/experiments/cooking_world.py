"""The cooking world of the PlanSys2 paper's experiment, as knowledge changes.

Robots fetch ingredients from the fridge, the pantry and the water tap to the
cooking zone and cook dishes there. A mission asks for two random dishes; when it
is done the next one is posted, as in the paper. The world is expressed as the
instances, facts and goal a problem expert receives, so the same generator feeds
the experiment, the demo mission and the tests.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

ZONES = ("cooking_zone", "fridge_zone", "pantry_zone", "watertap_zone", "recharge_zone")
ZONE_PREDICATE = {
    "cooking_zone": "is_cooking_zone",
    "fridge_zone": "is_fridge_zone",
    "pantry_zone": "is_pantry_zone",
    "watertap_zone": "is_watertap_zone",
    "recharge_zone": "is_recharge_zone",
}

# ingredient kind -> (predicate, zone where it is stored)
INGREDIENTS = {
    "egg": ("is_egg", "fridge_zone"),
    "oil": ("is_oil", "pantry_zone"),
    "salt": ("is_salt", "pantry_zone"),
    "flour": ("is_flour", "pantry_zone"),
    "sugar": ("is_sugar", "pantry_zone"),
    "pasta": ("is_pasta", "pantry_zone"),
    "water": ("is_water", "watertap_zone"),
}

# dish kind -> (predicate, ingredient kinds)
RECIPES = {
    "omelette": ("is_omelette", ("egg", "oil", "salt")),
    "cake": ("is_cake", ("flour", "egg", "sugar")),
    "spaghetti": ("is_spaghetti", ("water", "pasta", "oil", "salt")),
}

PAPER_DURATIONS = {"move": 3.8, "transport": 8.8, "cook": 21.0, "recharge": 10.0}
ROBOT_ACTIONS = ("move", "transport", "recharge", "cook_omelette", "cook_cake", "cook_spaghetti")


def cooking_domain_path() -> Path:
    """The cooking domain with the paper's durations, kept in configs/pddl."""
    from plansys_bridge.mission import default_missions_dir

    return default_missions_dir() / "pddl" / "cooking_domain.pddl"


def robot_names(count: int) -> list[str]:
    return [f"robot{i + 1}" for i in range(count)]


@dataclass(frozen=True)
class WorldSetup:
    """Static part of the world: zones, robots, where robots start."""

    instances: dict[str, str]
    predicates: list[str]


def world_setup(robots: int) -> WorldSetup:
    instances = {z: "zone" for z in ZONES}
    predicates = [f"({ZONE_PREDICATE[z]} {z})" for z in ZONES]
    for r in robot_names(robots):
        instances[r] = "robot"
        predicates += [f"(robot_at {r} cooking_zone)", f"(battery_full {r})"]
    return WorldSetup(instances, predicates)


@dataclass(frozen=True)
class DishOrder:
    """One mission: the dishes asked for and the ingredients brought in for them."""

    number: int
    dishes: tuple[tuple[str, str], ...]
    """(dish instance, dish kind)"""
    instances: dict[str, str]
    predicates: list[str]
    goal: str


def dish_order(
    number: int, rng: random.Random, dishes: int = 2, robots: Sequence[str] = ()
) -> DishOrder:
    """A mission of ``dishes`` random dishes, each with fresh ingredient instances.

    The goal also asks every robot in ``robots`` to end with a full battery: a robot
    whose battery dropped is recharged as part of the next plan instead of being
    left idle for the rest of the run.
    """
    instances: dict[str, str] = {}
    predicates: list[str] = []
    chosen: list[tuple[str, str]] = []
    for k in range(dishes):
        kind = rng.choice(sorted(RECIPES))
        dish = f"{kind}_{number}_{k}"
        pred, ingredients = RECIPES[kind]
        instances[dish] = "dish"
        predicates.append(f"({pred} {dish})")
        for ing in ingredients:
            name = f"{ing}_{number}_{k}"
            ipred, zone = INGREDIENTS[ing]
            instances[name] = "ingredient"
            predicates += [f"({ipred} {name})", f"(ingredient_at {name} {zone})"]
        chosen.append((dish, kind))
    parts = [f"(dish_prepared {d})" for d, _ in chosen] + [f"(battery_full {r})" for r in robots]
    goal = "(and " + " ".join(parts) + ")"
    return DishOrder(number, tuple(chosen), instances, predicates, goal)
