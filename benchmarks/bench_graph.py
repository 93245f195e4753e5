"""Plan graph and behaviour tree build time for plans of 100 to 5,000 actions.

The generated world: R robots (one per 20 actions) and R crates in a ring of 12
zones. Robots go round the ring; a robot that finds a crate where it is carries it
to the next zone, leaves it there and moves on. Crates are left for whichever
robot comes next, so the graph has per-robot chains plus many cross-robot causal links
and threats (column ``cross``: edges between actions of different robots).

Columns: plan size, robots, edges kept after transitive reduction, time to build
the graph (grounding, simulating and checking every happening, ordering,
reduction), time to compile the py_trees tree, and their sum.

Run::

    python benchmarks/bench_graph.py [--sizes 100 500 1000 5000] \\
        [--repeat 3] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from typing import Any

from plansys_bridge.clock import WallClock
from plansys_bridge.execution.behaviours import PlanContext
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.tree_builder import build_tree
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Atom, Domain
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.planning.plan import Plan, PlanStep
from plansys_bridge.planning.plan_graph import build_plan_graph

DOMAIN = """
(define (domain ring)
  (:requirements :typing :durative-actions)
  (:types robot zone crate)
  (:predicates (robot_at ?r - robot ?z - zone) (crate_at ?c - crate ?z - zone)
               (next ?a ?b - zone))
  (:durative-action move
    :parameters (?r - robot ?a ?b - zone)
    :duration (= ?duration 4)
    :condition (and (at start (robot_at ?r ?a)) (over all (next ?a ?b)))
    :effect (and (at start (not (robot_at ?r ?a))) (at end (robot_at ?r ?b))))
  (:durative-action transport
    :parameters (?r - robot ?c - crate ?a ?b - zone)
    :duration (= ?duration 6)
    :condition (and (at start (robot_at ?r ?a)) (at start (crate_at ?c ?a)) (over all (next ?a ?b)))
    :effect (and (at start (not (robot_at ?r ?a))) (at start (not (crate_at ?c ?a)))
                 (at end (robot_at ?r ?b)) (at end (crate_at ?c ?b))))
)
"""

ZONES = 12


def world(actions: int, robots: int | None = None) -> tuple[Domain, ProblemExpert, Plan]:
    """A knowledge base and a valid plan of exactly ``actions`` steps.

    ``robots`` defaults to one per 20 actions; a fixed count makes plans longer per
    robot (what execution cost linear in plan length is measured with)."""
    domain = parse_domain(DOMAIN, "<ring>")
    robots = robots if robots is not None else max(1, actions // 20)
    k = ProblemExpert(domain)
    with k.transaction():
        for z in range(ZONES):
            k.add_instance(f"z{z}", "zone")
        for z in range(ZONES):
            k.add_predicate(Atom("next", (f"z{z}", f"z{(z + 1) % ZONES}")))
        for r in range(robots):
            k.add_instance(f"r{r}", "robot")
            k.add_instance(f"c{r}", "crate")
            k.add_predicate(Atom("robot_at", (f"r{r}", f"z{r % ZONES}")))
            k.add_predicate(Atom("crate_at", (f"c{r}", f"z{r % ZONES}")))
    # simulate positions to emit a valid plan, round robin over robots
    robot_zone = {r: r % ZONES for r in range(robots)}
    clock = {r: 0.0 for r in range(robots)}
    ready = {c: 0.0 for c in range(robots)}  # when each crate arrived where it is
    at_zone: dict[int, list[int]] = {z: [] for z in range(ZONES)}
    for c in range(robots):
        at_zone[c % ZONES].append(c)
    carried = {r: False for r in range(robots)}  # a robot leaves its crate and moves on
    steps: list[PlanStep] = []
    turn = 0
    while len(steps) < actions:
        r = turn % robots
        turn += 1
        here = robot_zone[r]
        there = (here + 1) % ZONES
        # take the crate that has waited here longest (often left by another robot)
        waiting = [c for c in at_zone[here] if ready[c] <= clock[r] + 10.0]
        if waiting and not carried[r]:
            c = min(waiting, key=lambda c: (ready[c], c))
            at_zone[here].remove(c)
            at_zone[there].append(c)
            start = max(clock[r], ready[c])
            args = (f"r{r}", f"c{c}", f"z{here}", f"z{there}")
            steps.append(PlanStep(start, "transport", args, 6.0))
            clock[r] = ready[c] = start + 6.001
            carried[r] = True
        else:
            carried[r] = False
            steps.append(PlanStep(clock[r], "move", (f"r{r}", f"z{here}", f"z{there}"), 4.0))
            clock[r] += 4.001
        robot_zone[r] = there
    return domain, k, Plan(tuple(steps)).sorted()


def measure(actions: int, repeat: int) -> dict[str, Any]:
    domain, knowledge, plan = world(actions)
    hub = Hub(InProcessTransport(), WallClock())
    options = ExecutorOptions()
    graph_times: list[float] = []
    tree_times: list[float] = []
    edges = cross = 0
    for _ in range(repeat):
        t0 = time.perf_counter()
        graph = build_plan_graph(plan, domain, knowledge.state(), evaluator=knowledge.evaluator)
        graph.check()
        t1 = time.perf_counter()
        ctx = PlanContext(
            hub=hub,
            knowledge=knowledge,
            evaluator=knowledge.evaluator,
            graph=graph,
            options=options,
            plan_id="bench",
            plan_index=0,
        )
        root = build_tree(ctx)
        t2 = time.perf_counter()
        graph_times.append(t1 - t0)
        tree_times.append(t2 - t1)
        edges = graph.graph.number_of_edges()
        cross = sum(
            1
            for a, b in graph.graph.edges
            if plan.steps[a].arguments[0] != plan.steps[b].arguments[0]
        )
        del root
    g = statistics.median(graph_times)
    t = statistics.median(tree_times)
    return {
        "actions": actions,
        "robots": max(1, actions // 20),
        "edges": edges,
        "cross_robot_edges": cross,
        "graph_s": g,
        "tree_s": t,
        "total_s": g + t,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 500, 1000, 5000])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = [measure(n, args.repeat) for n in args.sizes]
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    head = ("actions", "robots", "edges", "cross", "graph s", "tree s", "total s", "ms/action")
    print(" ".join(f"{h:>9}" for h in head))
    for row in rows:
        print(
            f"{row['actions']:>9} {row['robots']:>9} {row['edges']:>9} "
            f"{row['cross_robot_edges']:>9} "
            f"{row['graph_s']:>9.3f} "
            f"{row['tree_s']:>9.3f} {row['total_s']:>9.3f} "
            f"{1000 * row['total_s'] / row['actions']:>9.3f}"
        )


if __name__ == "__main__":
    main()
