"""How fast the knowledge layer is on large generated problems.

Run: ``python benchmarks/knowledge_bench.py [--rooms N] [--steps N]``.

Measures what the executor and validator do most: loading a big problem, checking a
ground action's conditions and applying its effects step after step along a long
plan, evaluating quantified goals, and computing a recursive derived predicate (the
transitive closure of a corridor).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain

DOMAIN = """
(define (domain corridor)
  (:requirements :strips :typing :adl :fluents :derived-predicates)
  (:types robot room crate)
  (:predicates (at ?r - robot ?x - room) (link ?a ?b - room) (reach ?a ?b - room)
               (on ?c - crate ?x - room) (carrying ?r - robot ?c - crate) (visited ?x - room))
  (:functions (moves ?r - robot) (length ?a ?b - room))
  (:derived (reach ?a ?b - room)
    (or (link ?a ?b) (exists (?c - room) (and (reach ?a ?c) (link ?c ?b)))))
  (:action drive
    :parameters (?r - robot ?a ?b - room)
    :precondition (and (at ?r ?a) (link ?a ?b) (>= (moves ?r) 0))
    :effect (and (not (at ?r ?a)) (at ?r ?b) (visited ?b)
                 (increase (moves ?r) (length ?a ?b))
                 (forall (?c - crate) (when (carrying ?r ?c) (and (not (on ?c ?a)) (on ?c ?b))))))
)
"""


def problem_text(rooms: int, robots: int, crates: int) -> str:
    objects = [f"room{i} - room" for i in range(rooms)]
    objects += [f"robot{i} - robot" for i in range(robots)]
    objects += [f"crate{i} - crate" for i in range(crates)]
    init = []
    for i in range(rooms - 1):
        init.append(f"(link room{i} room{i + 1})")
        init.append(f"(link room{i + 1} room{i})")
        init.append(f"(= (length room{i} room{i + 1}) 1)")
        init.append(f"(= (length room{i + 1} room{i}) 1)")
    for r in range(robots):
        init.append(f"(at robot{r} room0)")
        init.append(f"(= (moves robot{r}) 0)")
    for c in range(crates):
        init.append(f"(on crate{c} room0)")
        if c < robots:
            init.append(f"(carrying robot{c} crate{c})")
    return (
        "(define (problem big) (:domain corridor)\n(:objects " + " ".join(objects) + ")\n"
        "(:init " + "\n".join(init) + ")\n"
        f"(:goal (forall (?r - robot) (at ?r room{rooms - 1}))))"
    )


def timed(label: str, fn: Callable[[], object], per: int = 1) -> object:
    start = time.perf_counter()
    result = fn()
    elapsed = time.perf_counter() - start
    extra = f"  ({elapsed / per * 1e6:.1f} us each over {per})" if per > 1 else ""
    print(f"{label:<48} {elapsed * 1000:9.1f} ms{extra}")
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rooms", type=int, default=2000)
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--crates", type=int, default=500)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--closure", type=int, default=200, help="rooms for the closure")
    args = parser.parse_args()

    de = DomainExpert(parse_domain(DOMAIN))
    text = problem_text(args.rooms, args.robots, args.crates)
    pe = ProblemExpert(de)
    timed(f"load problem ({len(text) // 1024} KiB)", lambda: pe.load_problem(text))
    ev = de.evaluator
    print(f"  {len(pe.state())} facts, {len(pe.state().fluents)} fluents")

    # a long plan: robots walk down the corridor in turn
    steps = []
    position = dict.fromkeys(range(args.robots), 0)
    for k in range(args.steps):
        r = k % args.robots
        a = position[r]
        b = a + 1 if a + 1 < args.rooms else a - 1
        position[r] = b
        steps.append(ev.ground_action("drive", [f"robot{r}", f"room{a}", f"room{b}"]))

    def run_plan() -> object:
        state = pe.state()
        for step in steps:
            if not ev.holds(step.over_all, state):
                raise SystemExit(f"{step} not applicable")
            state = ev.apply(step.end_effect, state)
        return state

    final = timed(f"check + apply {args.steps} steps", run_plan, per=args.steps)
    state = pe.state()
    goal = pe.get_goal()
    assert goal is not None
    timed("quantified goal (1000x)", lambda: [ev.holds(goal, final) for _ in range(1000)], per=1000)  # type: ignore[arg-type]
    step = steps[0]
    timed(
        "precondition tick (10000x)",
        lambda: [ev.holds(step.over_all, state) for _ in range(10000)],
        per=10000,
    )

    notices: list[object] = []
    pe.subscribe(notices.append)
    live = steps[:1000]

    def apply_live() -> None:
        for step in live:
            pe.apply(step.end_effect)

    timed(
        f"apply to the live knowledge, notified ({len(live)}x, {len(pe.get_instances())} objects)",
        apply_live,
        per=len(live),
    )
    assert len(notices) == len(live)

    small = ProblemExpert(de)
    small.load_problem(problem_text(args.closure, 1, 0))
    timed(
        f"transitive closure over {args.closure} rooms",
        lambda: ev.derived_facts(small.state())["reach"],
    )
    pe2 = ProblemExpert(de)
    pe2.load_problem(problem_text(200, 1, 0))

    def single_adds() -> None:
        for i in range(args.steps):
            pe2.add_predicate(f"(visited room{i % 200})")

    timed(f"add_predicate from text ({args.steps}x)", single_adds, per=args.steps)


if __name__ == "__main__":
    main()
