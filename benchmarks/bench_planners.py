"""Every available solver on the same tasks: time, plan length, makespan, validity.

Tasks:

* the cooking world of the PlanSys2 paper (configs/pddl/cooking_domain.pddl, the
  paper's durations: move 3.8 s, transport 8.8 s, cook 21 s) with 1-3 robots and
  1-12 dishes, generated with :mod:`plansys_bridge.experiments.cooking_world`;
* PlanSys2's factory (plansys2_executor's factory.pddl + problem_factory_1.pddl);
* a generated large task: R robots cleaning N rooms around a hub (durative).

Every solver the planner knows is tried on every task with a per-solver timeout
(solvers that are not installed or lack a feature the task uses are listed once).
Columns: status; ``time`` = wall time of ``Planner.solve`` (capability check,
writing the PDDL, the solver, reading its plan: the project's overhead included);
plan length; makespan as planned and after rescheduling on the executor's plan
graph; whether our validator accepts the plan (with the solver's separation) and
the rescheduled plan; ``check`` = time to validate and reschedule.

Run::

    python benchmarks/bench_planners.py [--timeout 20] [--quick]
        [--solvers kairos lpg ...] [--improve 2] [--json]
"""

from __future__ import annotations

import argparse
import json
import random
import sys
import time
from dataclasses import dataclass
from typing import Any

from bench_support import FIXTURES

from plansys_bridge.experiments.cooking_world import cooking_domain_path, dish_order, world_setup
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.pddl.parser import parse_domain, parse_problem
from plansys_bridge.planning.capabilities import describe, required_capabilities
from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.result import PlanStatus
from plansys_bridge.planning.schedule import reschedule_report
from plansys_bridge.planning.solvers import load_solver, solver_names
from plansys_bridge.planning.validation import validate_plan

FACTORY = FIXTURES / "ros2_planning_system/plansys2_executor/test/pddl"

LARGE_DOMAIN = """
(define (domain cleaning)
  (:requirements :strips :typing :durative-actions)
  (:types robot room)
  (:predicates (robot_at ?r - robot ?x - room) (connected ?a ?b - room)
               (cleaned ?x - room) (free ?x - room))
  (:durative-action move
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration 4)
    :condition (and (at start (robot_at ?r ?a)) (over all (connected ?a ?b))
                    (at start (free ?b)))
    :effect (and (at start (not (robot_at ?r ?a))) (at start (not (free ?b)))
                 (at end (free ?a)) (at end (robot_at ?r ?b))))
  (:durative-action clean
    :parameters (?r - robot ?x - room)
    :duration (= ?duration 10)
    :condition (and (over all (robot_at ?r ?x)))
    :effect (and (at end (cleaned ?x)))))
"""


@dataclass(frozen=True)
class Task:
    name: str
    domain: Domain
    problem: Problem


def cooking_problem(domain: Domain, robots: int, dishes: int, seed: int = 7) -> Problem:
    setup = world_setup(robots)
    order = dish_order(1, random.Random(seed), dishes=dishes)
    instances = {**setup.instances, **order.instances}
    objects = "\n".join(f"    {name} - {kind}" for name, kind in instances.items())
    init = "\n".join(f"    {fact}" for fact in setup.predicates + order.predicates)
    text = (
        f"(define (problem cooking_r{robots}_d{dishes}) (:domain cooking)\n"
        f"  (:objects\n{objects})\n  (:init\n{init})\n  (:goal {order.goal}))\n"
    )
    return parse_problem(text, domain, f"cooking_r{robots}_d{dishes}")


def large_problem(domain: Domain, robots: int, rooms: int) -> Problem:
    """A hub with ``rooms`` rooms around it; robots start in the first rooms."""
    names = [f"room{i}" for i in range(rooms)]
    init = [f"(connected hub {r}) (connected {r} hub)" for r in names]
    for i, r in enumerate(names):
        init.append(f"(robot_at robot{i} {r})" if i < robots else f"(free {r})")
    init.append("(free hub)")
    goal = " ".join(f"(cleaned {r})" for r in names)
    text = (
        f"(define (problem cleaning_r{robots}_n{rooms}) (:domain cleaning)\n"
        f"  (:objects {' '.join(f'robot{i}' for i in range(robots))} - robot "
        f"hub {' '.join(names)} - room)\n"
        f"  (:init {' '.join(init)})\n  (:goal (and {goal})))\n"
    )
    return parse_problem(text, domain, f"cleaning_r{robots}_n{rooms}")


def build_tasks(quick: bool) -> list[Task]:
    cooking = parse_domain(cooking_domain_path().read_text(), str(cooking_domain_path()))
    out = []
    dish_counts = (1, 3, 12) if quick else (1, 2, 3, 6, 12)
    for robots in (1, 2, 3):
        for dishes in dish_counts:
            out.append(
                Task(
                    f"cooking r{robots} d{dishes}",
                    cooking,
                    cooking_problem(cooking, robots, dishes),
                )
            )
    if FACTORY.is_dir():
        factory = parse_domain((FACTORY / "factory.pddl").read_text(), "factory.pddl")
        problem = parse_problem(
            (FACTORY / "problem_factory_1.pddl").read_text(), factory, "problem_factory_1.pddl"
        )
        out.append(Task("factory", factory, problem))
    cleaning = parse_domain(LARGE_DOMAIN, "cleaning")
    out.append(Task("large r6 n30", cleaning, large_problem(cleaning, 6, 30)))
    return out


def variants(solvers: list[str], improve: float) -> list[tuple[str, str, dict[str, Any]]]:
    """(label, solver, options): every solver as configured by default, plus Kairos with
    an anytime budget."""
    out: list[tuple[str, str, dict[str, Any]]] = [(name, name, {}) for name in solvers]
    if improve > 0 and "kairos" in solvers:
        out.insert(1, (f"kairos+{improve:g}s", "kairos", {"improve_for": improve}))
    return out


def run(
    tasks: list[Task], configs: list[tuple[str, str, dict[str, Any]]], timeout: float
) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = []
    for task in tasks:
        required = required_capabilities(task.domain, task.problem)
        for label, name, options in configs:
            planner = Planner([name], timeout=timeout, options=options)
            solver = planner.solvers[0]
            if solver.availability() is not None or solver.missing_capabilities(required):
                continue
            started = time.perf_counter()
            result = planner.solve(task.domain, task.problem)
            wall = time.perf_counter() - started
            row: dict[str, Any] = {
                "task": task.name,
                "solver": label,
                "status": result.status.value,
                "time_s": wall,
                "steps": None,
                "makespan": None,
                "rescheduled": None,
                "valid": None,
                "valid_after": None,
                "check_s": None,
                "message": "" if result.solved else result.message[:160],
            }
            if result.plan is not None:
                t0 = time.perf_counter()
                eps = solver.epsilon
                report = validate_plan(task.domain, task.problem, result.plan, epsilon=eps)
                after = reschedule_report(result.plan, task.domain, task.problem, epsilon=eps)
                valid_after = (
                    validate_plan(task.domain, task.problem, after.plan, epsilon=eps).valid
                    if after.rescheduled
                    else report.valid
                )
                row.update(
                    steps=len(result.plan),
                    makespan=result.plan.makespan,
                    rescheduled=after.makespan_after,
                    valid=report.valid,
                    valid_after=valid_after,
                    check_s=time.perf_counter() - t0,
                )
                if not report.valid:
                    row["message"] = report.message[:160]
            rows.append(row)
            print(_line(row), flush=True)
    return rows


HEADER = (
    f"{'task':18} {'solver':16} {'status':11} {'time s':>8} {'steps':>5} "
    f"{'makespan':>9} {'resched.':>9} {'valid':>5} {'after':>5} {'check s':>8}"
)


def _fmt(value: Any, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def _line(row: dict[str, Any]) -> str:
    valid = {True: "yes", False: "NO", None: "-"}
    text = (
        f"{row['task']:18} {row['solver']:16} {row['status']:11} {row['time_s']:8.3f} "
        f"{_fmt(row['steps'], '5d')} {_fmt(row['makespan'], '9.3f')} "
        f"{_fmt(row['rescheduled'], '9.3f')} {valid[row['valid']]:>5} "
        f"{valid[row['valid_after']]:>5} {_fmt(row['check_s'], '8.3f')}"
    )
    if row["message"]:
        text += f"\n{'':18} {row['message']}"
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--timeout", type=float, default=20.0, help="per solver and task (s)")
    parser.add_argument("--solvers", nargs="*", default=None)
    parser.add_argument("--quick", action="store_true", help="fewer cooking sizes")
    parser.add_argument(
        "--improve", type=float, default=2.0, help="Kairos anytime budget (s); 0: no such row"
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    solvers = args.solvers or solver_names()
    t0 = time.perf_counter()
    tasks = build_tasks(args.quick)
    print(f"tasks built in {time.perf_counter() - t0:.1f} s: {', '.join(t.name for t in tasks)}")
    for name in solvers:
        reason = load_solver(name).unavailable_reason()
        caps = describe(load_solver(name).capabilities)
        print(f"  {name:16} {'available' if reason is None else reason}; features {caps}")
    features: dict[str, str] = {}
    for task in tasks:
        kind = task.name.split()[0]
        features.setdefault(kind, describe(required_capabilities(task.domain, task.problem)))
    print("  task features: " + "; ".join(f"{k}: {v}" for k, v in features.items()))
    print(HEADER)
    configs = variants(solvers, args.improve)
    rows = run(tasks, configs, args.timeout)
    print(f"total {time.perf_counter() - t0:.1f} s")
    solved = [r for r in rows if r["status"] == PlanStatus.SOLVED.value]
    for label, _, _ in configs:
        mine = [r for r in rows if r["solver"] == label]
        if mine:
            ok = [r for r in mine if r["status"] == "solved" and r["valid"]]
            gains = [r["makespan"] - r["rescheduled"] for r in ok]
            print(
                f"  {label:16} {len(ok)}/{len(mine)} tasks with a valid plan; "
                f"rescheduling gained {sum(gains):.3f} s of makespan in total"
            )
    if args.json:
        json.dump(rows, sys.stdout, indent=1)
    return 0 if solved else 1


if __name__ == "__main__":
    raise SystemExit(main())
