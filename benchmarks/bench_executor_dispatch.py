"""Executor dispatch latency on the real clock: predecessor FINISH to successor start.

A plan is a chain of N ``step`` actions round a ring of 10 spots (each needs the
previous one's at-end effect), served by one performer on the in-process hub. For each pair of
consecutive actions it measures, with ``time.perf_counter``:

* FINISH -> successor EXECUTING: from the predecessor's performer sending FINISH
  to the executor applying the successor's at-start effects and starting its
  ``ExecuteAction`` (the tree's part: the event-driven tick);
* FINISH -> successor performer executing: to the performer's ``execute()``
  starting for the successor (adds the auction: REQUEST, RESPONSE, CONFIRM).

PlanSys2 ticks its tree at 10 Hz, so its successor starts up to 100 ms late.

Run: ``python benchmarks/bench_executor_dispatch.py [--actions N] [--json]``
"""

from __future__ import annotations

import argparse
import json
import time

from bench_support import StampingPerformer, summary

from plansys_bridge.clock import WallClock, run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecutionInfo, ActionStatus
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Atom, Domain
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.planning.plan import Plan, PlanStep

DOMAIN = """
(define (domain chain)
  (:requirements :typing :durative-actions)
  (:types robot spot)
  (:predicates (at ?r - robot ?s - spot))
  (:durative-action step
    :parameters (?r - robot ?a ?b - spot)
    :duration (= ?duration 1)
    :condition (at start (at ?r ?a))
    :effect (and (at start (not (at ?r ?a))) (at end (at ?r ?b))))
)
"""


SPOTS = 10
"""The robot goes round a ring of spots (a small knowledge base, as on a robot)."""


def chain_task(actions: int) -> tuple[Domain, ProblemExpert, Plan]:
    """The chain's domain, its knowledge (r1 at s0) and the plan of ``actions`` steps."""
    domain = parse_domain(DOMAIN, "<chain>")
    knowledge = ProblemExpert(domain)
    with knowledge.transaction():
        knowledge.add_instance("r1", "robot")
        for i in range(SPOTS):
            knowledge.add_instance(f"s{i}", "spot")
        knowledge.add_predicate(Atom("at", ("r1", "s0")))
    plan = Plan(
        tuple(
            PlanStep(i * 1.001, "step", ("r1", f"s{i % SPOTS}", f"s{(i + 1) % SPOTS}"), 1.0)
            for i in range(actions)
        )
    )
    return domain, knowledge, plan


async def _bench(actions: int) -> dict[str, dict[str, float]]:
    domain, knowledge, plan = chain_task(actions)
    hub = Hub(InProcessTransport(), WallClock())
    await hub.start()
    performer = StampingPerformer(PerformerContext(hub, hub.clock), "worker", {"step": ["r1"]})
    performer.work_s = 0.001
    await performer.start()
    executing: list[float] = []  # the chain starts its actions one after the other

    def on_info(info: ActionExecutionInfo) -> None:
        if (
            info.status == ActionStatus.EXECUTING
            and info.completion == 0.0
            and not info.message_status
        ):
            executing.append(time.perf_counter())

    executor = Executor(hub, domain, knowledge, None, ExecutorOptions(publish_dot=False))
    result = await executor.execute(plan, plan_id="chain", on_info=on_info)
    await performer.stop()
    await hub.close()
    if not result.success:
        raise RuntimeError(f"chain failed: {result.message}")
    assert len(executing) == actions, (len(executing), actions)
    to_executing: list[float] = []
    to_performer: list[float] = []
    warmup = min(20, actions // 10)
    for i in range(1 + warmup, actions):
        finish = performer.finished[f"chain/0/{i - 1}"]
        to_executing.append(executing[i] - finish)
        to_performer.append(performer.started[f"chain/0/{i}"] - finish)
    return {
        "finish_to_successor_executing": summary(to_executing),
        "finish_to_successor_performer": summary(to_performer),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--actions", type=int, default=1000)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    results = run(_bench(args.actions), WallClock())
    if args.json:
        print(json.dumps(results, indent=2))
        return
    print(f"Executor dispatch on the wall clock, chain of {args.actions} actions, in-process hub")
    header = f"{'measure':<32} {'median':>9} {'p90':>9} {'p99':>9} {'max':>9}  (us)"
    print(header)
    print("-" * len(header))
    for name, s in results.items():
        print(
            f"{name:<32} {s['median_us']:>9.1f} {s['p90_us']:>9.1f} "
            f"{s['p99_us']:>9.1f} {s['max_us']:>9.1f}"
        )


if __name__ == "__main__":
    main()
