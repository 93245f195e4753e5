"""The knowledge's share of an executed action: the calls the executor makes into it.

Per action the executor (execution/plan_context.py and execution/phases.py) asks
whether a ground condition holds four times (at start once, over all twice: when
the performer is confirmed and when it ends, at end once; each on the current
snapshot) and applies the at-start and at-end effects, each notifying a subscriber
(the at-start effect's delta, which a halt undoes, is what ``apply`` reports it
changed). This replays exactly those calls along the ring plans of
``bench_graph.py`` (no hub, no tree, no clock), so what is measured
is the knowledge alone: CPU time per action (best of ``--repeat`` runs) and, with
``--calls``, the Python calls per action under cProfile (a figure that does not
swing with the machine's speed). There is no peer to compare with.

Run::

    python benchmarks/bench_knowledge_per_action.py [--actions 1000] [--robots 10]
        [--repeat 5] [--calls]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from bench_graph import world

from plansys_bridge.execution.effect_delta import EffectDelta
from plansys_bridge.knowledge.evaluation import GroundAction
from plansys_bridge.knowledge.problem_expert import KnowledgeChange, ProblemExpert
from plansys_bridge.planning.orderings import GROUND
from plansys_bridge.planning.plan import Plan


def _ground(knowledge: ProblemExpert, plan: Plan) -> list[tuple[GroundAction, float]]:
    """Each step's ground action, one object per distinct action (as the plan graph
    shares them), with the step's duration."""
    ev = knowledge.evaluator
    made: dict[tuple[str, tuple[str, ...]], GroundAction] = {}
    out = []
    for step in plan.steps:
        key = (step.action, step.arguments)
        if key not in made:
            made[key] = ev.ground_action(step.action, step.arguments, knowledge.state())
        out.append((made[key], step.duration))
    return out


def replay(knowledge: ProblemExpert, steps: list[tuple[GroundAction, float]]) -> int:
    """The executor's knowledge calls for every step in turn; how many notices came."""
    ev = knowledge.evaluator
    notices: list[KnowledgeChange] = []
    knowledge.subscribe(notices.append)
    for ground, duration in steps:
        ev.holds(ground.at_start, knowledge.state(), GROUND, duration)
        applied = knowledge.apply(ground.start_effect, GROUND, duration)
        EffectDelta(applied.added, applied.deleted, applied.fluents)
        for cond in (ground.over_all, ground.over_all, ground.at_end):
            ev.holds(cond, knowledge.state(), GROUND, duration)
        knowledge.apply(ground.end_effect, GROUND, duration)
    return len(notices)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--actions", type=int, default=1000)
    parser.add_argument("--robots", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=5, help="runs (best kept)")
    parser.add_argument("--calls", action="store_true", help="Python calls per action")
    args = parser.parse_args()
    best = float("inf")
    notices = 0
    for _ in range(args.repeat):
        _domain, knowledge, plan = world(args.actions, args.robots)
        steps = _ground(knowledge, plan)
        c0 = time.process_time()
        notices = replay(knowledge, steps)
        best = min(best, time.process_time() - c0)
    print(f"{args.actions} actions, {args.robots} robots, {notices} notices")
    print(f"knowledge CPU per action: {best / args.actions * 1e6:.2f} us (best of {args.repeat})")
    if args.calls:
        _domain, knowledge, plan = world(args.actions, args.robots)
        steps = _ground(knowledge, plan)
        profile = cProfile.Profile()
        profile.runcall(replay, knowledge, steps)
        calls = pstats.Stats(profile).total_calls  # type: ignore[attr-defined]
        print(f"Python calls per action: {calls / args.actions:.1f}")


if __name__ == "__main__":
    main()
