"""Helpers for executor tests: fixture PDDL, knowledge, and runs on the virtual clock.

Every executor test runs on the :class:`VirtualClock`, so a mission of minutes takes
milliseconds and timings are exact and reproducible.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from pddl_corpus import FIXTURES

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer
from plansys_bridge.planning.planner import Planner

EXECUTOR_PDDL = FIXTURES / "ros2_planning_system/plansys2_executor/test/pddl"


def load_domain(name: str) -> Domain:
    path = EXECUTOR_PDDL / name
    return parse_domain(path.read_text(), str(path))


def knowledge_from(
    domain: Domain,
    problem: str | None = None,
    *,
    instances: Mapping[str, str] = {},
    facts: Sequence[str] = (),
    functions: Sequence[str] = (),
    goal: str | None = None,
) -> ProblemExpert:
    """A problem expert loaded from a fixture problem file or from explicit items."""
    k = ProblemExpert(domain)
    if problem is not None:
        k.load_problem((EXECUTOR_PDDL / problem).read_text(), str(EXECUTOR_PDDL / problem))
    with k.transaction():
        for name, type_name in instances.items():
            k.add_instance(name, type_name)
        for fact in facts:
            k.add_predicate(fact)
        for fv in functions:
            k.set_function(fv)
        if goal is not None:
            k.set_goal(goal)
    return k


@dataclass
class PerformerSpec:
    """A simulated performer: node name, {action: specialised args}, durations."""

    name: str
    actions: Mapping[str, Sequence[str]]
    durations: Mapping[str, float] = field(default_factory=dict)
    settings: Mapping[str, Any] = field(default_factory=dict)


@dataclass
class Run:
    """What a scenario produced."""

    result: ExecutionResult
    messages: list[tuple[float, str, object]]
    performers: dict[str, SimulatedPerformer]

    def of_topic(self, topic: str) -> list[object]:
        return [m for _, t, m in self.messages if t == topic]


Event = tuple[float, Callable[[ProblemExpert, Executor], None]]


def run_scenario(
    domain: Domain,
    knowledge: ProblemExpert,
    body: Callable[[Executor], Awaitable[ExecutionResult]],
    performers: Sequence[PerformerSpec],
    *,
    options: ExecutorOptions | None = None,
    planner: Planner | None = None,
    events: Sequence[Event] = (),
    topics: Sequence[str] = (),
) -> Run:
    """Start hub + performers on a virtual clock, run ``body(executor)``, stop all."""
    clock = VirtualClock()

    async def main() -> Run:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        messages: list[tuple[float, str, object]] = []

        def recorder(topic: str) -> Callable[[object], None]:
            return lambda msg: messages.append((clock.now(), topic, msg))

        subs = [hub.subscribe(t, recorder(t)) for t in topics]
        ctx = PerformerContext(hub, clock, knowledge)
        started: dict[str, SimulatedPerformer] = {}
        for spec in performers:
            perf = SimulatedPerformer(
                ctx, spec.name, spec.actions, durations=spec.durations, **spec.settings
            )
            await perf.start()
            started[spec.name] = perf
        executor = Executor(hub, domain, knowledge, planner, options or ExecutorOptions())
        loop = asyncio.get_running_loop()
        handles = [loop.call_later(t, fn, knowledge, executor) for t, fn in events]
        try:
            result = await body(executor)
        finally:
            for h in handles:
                h.cancel()
            for perf in started.values():
                await perf.stop()
            for sub in subs:
                sub.close()
            await hub.close()
        return Run(result, messages, started)

    return run(main(), clock)


def per_robot_performers(
    robots: Sequence[str],
    actions: Sequence[str],
    durations: Mapping[str, float],
    robot_position: int = 0,
) -> list[PerformerSpec]:
    """One performer per (robot, action) that serves only that robot (specialised arguments)."""
    specs = []
    for robot in robots:
        for action in actions:
            args = [""] * robot_position + [robot]
            specs.append(
                PerformerSpec(f"{action}_{robot}", {action: args}, {action: durations[action]})
            )
    return specs


def overlap(intervals: Sequence[tuple[float, float]]) -> float:
    """Total time during which at least two of ``intervals`` run at once."""
    points = sorted(
        [(s, 1) for s, _ in intervals] + [(e, -1) for _, e in intervals], key=lambda p: (p[0], p[1])
    )
    active, last, total = 0, 0.0, 0.0
    for t, delta in points:
        if active >= 2:
            total += t - last
        active += delta
        last = t
    return total


DOOR_DOMAIN = """
(define (domain door)
  (:requirements :typing :durative-actions :fluents)
  (:types robot door)
  (:predicates (door_open ?d - door) (passed ?r - robot ?d - door))
  (:functions (total-cost))
  (:durative-action hold_open
    :parameters (?r - robot ?d - door)
    :duration (= ?duration 10)
    :condition (and)
    :effect (and (at start (door_open ?d)) (at end (not (door_open ?d)))
                 (at end (increase (total-cost) 1))))
  (:durative-action pass
    :parameters (?r - robot ?d - door)
    :duration (= ?duration 3)
    :condition (and (at start (door_open ?d)) (over all (door_open ?d)))
    :effect (and (at end (passed ?r ?d)) (at end (increase (total-cost) 1))))
)
"""


def door_setup() -> tuple[Domain, ProblemExpert]:
    """A door one robot holds open while others pass (required concurrency)."""
    domain = parse_domain(DOOR_DOMAIN)
    k = knowledge_from(
        domain,
        instances={"holder": "robot", "walker": "robot", "walker2": "robot", "d1": "door"},
        functions=["(= (total-cost) 0)"],
    )
    return domain, k
