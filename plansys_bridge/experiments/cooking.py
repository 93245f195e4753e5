"""The PlanSys2 paper's cooking experiment, and its soak variant.

Robots keep cooking: a mission of two random dishes is posted, planned, executed
(replanning when a battery drops mid-action), and when it ends the next one is
posted, for a given number of hours of mission time or plans. The figures are the
paper's: plans, actions, replans, failures, dishes and the *efficiency*, the summed
execution time of actions over the total time (above 100 % with parallel robots).

Each robot has one simulated performer per action, as the PlanSys2 experiment ran
one action node per action, with the paper's durations. With faults switched on
(the soak run), performers die mid-action and come back, FINISH messages get lost,
performers stop answering for a while, and batteries drop; the run checks after
every plan that the knowledge is still consistent.
"""

from __future__ import annotations

import asyncio
import random
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.clock import Clock, VirtualClock, WallClock, run
from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.experiments.cooking_world import (
    PAPER_DURATIONS,
    ROBOT_ACTIONS,
    DishOrder,
    cooking_domain_path,
    dish_order,
    robot_names,
    world_setup,
)
from plansys_bridge.hub.auction import AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.model import Domain, Problem
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import FaultPlan, SimulatedPerformer
from plansys_bridge.planning.balance import balance_plan, executed_makespan
from plansys_bridge.planning.planner import Planner
from plansys_bridge.planning.result import PlanResult

__all__ = [
    "PAPER_EFFICIENCY",
    "CookingConfig",
    "CookingStats",
    "PortfolioPlanner",
    "executed_makespan",
    "run_cooking",
]

PAPER_EFFICIENCY = {1: 95.15, 2: 137.54, 3: 182.11}
"""Table I of the PlanSys2 paper: efficiency (%) with 1, 2 and 3 robots."""


@dataclass(frozen=True)
class CookingConfig:
    robots: int = 3
    hours: float = 1.0
    """Mission time to run, at the paper's scale."""
    max_plans: int | None = None
    """Stop after this many missions instead (the soak run)."""
    clock: Literal["virtual", "wall"] = "virtual"
    time_scale: float = 1.0
    seed: int = 1
    dishes_per_mission: int = 2
    battery_drops_per_hour: float = 2.0
    """Per robot: how often (mission time) a battery drops and must be recharged."""
    max_replans: int = 5
    faults: FaultPlan = field(default_factory=FaultPlan)
    unresponsive_per_hour: float = 0.0
    """How often a random performer stops answering REQUESTs for a while."""
    unresponsive_for: float = 60.0
    auction: AuctionPolicy = field(
        default_factory=lambda: AuctionPolicy(give_up_after=30.0, liveness_timeout=5.0)
    )
    domain_path: Path = field(default_factory=cooking_domain_path)
    plan_portfolio: bool = True
    """Plan with several Kairos configurations and keep the plan the robots finish
    first (see :class:`PortfolioPlanner`); False: Kairos' first plan, as PlanSys2."""
    on_plan: Callable[[int, ExecutionResult], None] | None = None


@dataclass
class CookingStats:
    robots: int
    clock: str
    time_scale: float
    plans: int = 0
    """Plans executed: one per mission plus one per replan."""
    missions: int = 0
    actions: int = 0
    replans: int = 0
    failures: int = 0
    """Missions that ended without their dishes."""
    dishes: int = 0
    total_time_s: float = 0.0
    """Mission time from the first order to the end of the last execution."""
    action_time_s: float = 0.0
    efficiency_percent: float = 0.0
    planning_s: float = 0.0
    wall_s: float = 0.0
    battery_drops: int = 0
    unresponsive_injected: int = 0
    performer_deaths: int = 0
    lost_finishes: int = 0
    reauctioned_actions: int = 0
    consistency_errors: list[str] = field(default_factory=list)
    failure_reasons: dict[str, int] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out = asdict(self)
        for k in ("total_time_s", "action_time_s", "efficiency_percent", "planning_s", "wall_s"):
            out[k] = round(out[k], 3)
        return out


PORTFOLIO: tuple[dict[str, str], ...] = (
    {"search": "ff"},
    {"engine": "m3"},
)
"""Kairos configurations tried besides its default for every plan."""


class PortfolioPlanner(Planner):
    """Kairos with its default search and the :data:`PORTFOLIO` ones, each plan balanced
    (:func:`~plansys_bridge.planning.balance.balance_plan`); keeps the plan whose robots
    finish first when each performer runs one action at a time.

    Kairos' first plan sometimes hands all the work of a mission to one robot (the
    others idle), or has one robot do two actions of one kind at once, which its single
    performer for that action then runs one after the other (both cooks of a mission to
    robot3: 54.6 s instead of 33.6). Another search often spreads the work over more
    robots, and balancing hands a doubled step to a robot that is free for it. The
    novelty search on Kairos' M3 engine found those plans too, but took 0.1-0.6 s
    (robots idle while a mission is planned, which costs on the wall clock), and on the
    missions of seeds 1-8 its plan was never shorter than the best balanced plan of
    these three, which take about 0.05 s. The configurations search at once, on
    threads (Kairos releases the GIL while it searches), so the portfolio costs about
    its slowest search rather than the sum.
    """

    def __init__(self) -> None:
        super().__init__()
        self.alternatives = [Planner(options={"kairos": dict(c)}) for c in PORTFOLIO]

    def solve(self, domain: Domain, problem: Problem) -> PlanResult:
        with ThreadPoolExecutor(max_workers=1 + len(self.alternatives)) as pool:
            first = pool.submit(super().solve, domain, problem)
            others = [pool.submit(p.solve, domain, problem) for p in self.alternatives]
            results = [first.result(), *(f.result() for f in others)]
        balanced = [_balanced(domain, problem, r) for r in results if r.solved]
        if not balanced:
            return results[0]
        return min(balanced, key=lambda b: b[1])[0]


def _balanced(domain: Domain, problem: Problem, result: PlanResult) -> tuple[PlanResult, float]:
    """The solver's result with its plan balanced, and the plan's executed makespan."""
    assert result.plan is not None
    balanced = balance_plan(domain, problem, result.plan)
    if not balanced.handoffs:
        return result, balanced.after
    moved = sum(len(h.steps) for h in balanced.handoffs)
    note = (
        f"balanced: {moved} step(s) handed to a free robot, executed makespan "
        f"{balanced.before:.3f} -> {balanced.after:.3f}"
    )
    message = f"{result.message}; {note}" if result.message else note
    return replace(result, plan=balanced.plan, message=message), balanced.after


def run_cooking(config: CookingConfig) -> CookingStats:
    """Run the experiment to its end on the clock the config names."""
    domain = parse_domain_files([config.domain_path])
    clock: Clock = (
        VirtualClock() if config.clock == "virtual" else WallClock(time_scale=config.time_scale)
    )
    wall0 = time.perf_counter()
    stats = run(_Experiment(config, domain, clock).run(), clock)
    stats.wall_s = time.perf_counter() - wall0
    return stats


class _Experiment:
    def __init__(self, config: CookingConfig, domain: Domain, clock: Clock) -> None:
        self.config = config
        self.domain = domain
        self.clock = clock
        self.rng = random.Random(config.seed)
        self.knowledge = ProblemExpert(domain)
        self.planner: Planner = PortfolioPlanner() if config.plan_portfolio else Planner()
        self.robots = robot_names(config.robots)
        self.stats = CookingStats(config.robots, config.clock, config.time_scale)
        self.performers: list[SimulatedPerformer] = []

    def _setup_world(self) -> None:
        world = world_setup(self.config.robots)
        with self.knowledge.transaction():
            for name, type_name in world.instances.items():
                self.knowledge.add_instance(name, type_name)
            for fact in world.predicates:
                self.knowledge.add_predicate(fact)

    def _performers(self, hub: Hub) -> list[SimulatedPerformer]:
        context = PerformerContext(hub=hub, clock=self.clock, knowledge=None, base_dir=Path("."))
        durations = {
            a: PAPER_DURATIONS["cook" if a.startswith("cook") else a] for a in ROBOT_ACTIONS
        }
        return [
            SimulatedPerformer(
                context,
                f"{robot}_{action}",
                {action: [robot]},
                durations=durations,
                seed=self.config.seed,
                feedback_period=2.0,
                faults=self.config.faults,
            )
            for robot in self.robots
            for action in ROBOT_ACTIONS
        ]

    async def run(self) -> CookingStats:
        cfg = self.config
        self._setup_world()
        hub = Hub(InProcessTransport(), self.clock)
        await hub.start()
        self.performers = self._performers(hub)
        for p in self.performers:
            await p.start()
        options = ExecutorOptions(
            auction=cfg.auction, max_replans=cfg.max_replans, at_start_timeout=30.0
        )
        executor = Executor(hub, self.domain, self.knowledge, self.planner, options)
        t0 = self.clock.now()
        end = t0 + cfg.hours * 3600.0
        injectors = [
            asyncio.get_running_loop().create_task(self._battery_drops()),
            asyncio.get_running_loop().create_task(self._unresponsive()),
        ]
        action_time = 0.0
        try:
            number = 0
            while True:
                if cfg.max_plans is not None:
                    if self.stats.missions >= cfg.max_plans:
                        break
                elif self.clock.now() >= end:
                    break
                number += 1
                result = await self._mission(
                    executor, dish_order(number, self.rng, cfg.dishes_per_mission, self.robots)
                )
                if result is not None:
                    action_time += sum(a.execution_time for a in result.actions)
                    if cfg.on_plan is not None:
                        cfg.on_plan(number, result)
        finally:
            await cancel_and_wait(*injectors)
            for p in self.performers:
                await p.stop()
            await hub.close()
        s = self.stats
        s.total_time_s = self.clock.now() - t0
        s.action_time_s = action_time
        s.efficiency_percent = 100.0 * action_time / s.total_time_s if s.total_time_s > 0 else 0.0
        s.performer_deaths = sum(p.stats["died"] for p in self.performers)
        s.lost_finishes = sum(p.stats["lost_finish"] for p in self.performers)
        return s

    async def _mission(self, executor: Executor, order: DishOrder) -> ExecutionResult | None:
        s = self.stats
        s.missions += 1
        with self.knowledge.transaction():
            for name, type_name in order.instances.items():
                self.knowledge.add_instance(name, type_name)
            for fact in order.predicates:
                self.knowledge.add_predicate(fact)
            self.knowledge.set_goal(order.goal)
        goal = self.knowledge.get_goal()
        result: ExecutionResult | None = None
        try:
            t = time.perf_counter()
            planned = await asyncio.to_thread(
                self.planner.solve, self.domain, self.knowledge.to_problem()
            )
            s.planning_s += time.perf_counter() - t
            if planned.plan is None:
                self._failed(f"no plan: {planned.status.name.lower()}")
                return None
            result = await executor.execute(planned.plan, goal=goal)
            s.plans += len(result.plans)
            s.replans += result.replans
            s.actions += len(result.actions)
            s.reauctioned_actions += sum(1 for a in result.actions if a.reauctioned)
            if result.success:
                s.dishes += len(order.dishes)
            else:
                self._failed(
                    result.status
                    + (f": {result.message.splitlines()[0]}" if result.message else "")
                )
            return result
        finally:
            self._cleanup(order)

    def _failed(self, reason: str) -> None:
        self.stats.failures += 1
        key = reason[:120]
        self.stats.failure_reasons[key] = self.stats.failure_reasons.get(key, 0) + 1

    def _cleanup(self, order: DishOrder) -> None:
        """Remove the order's dishes and ingredients, then check the knowledge."""
        with self.knowledge.transaction():
            self.knowledge.clear_goal()
            for name in order.instances:
                self.knowledge.remove_instance(name)
        self._check_consistency(order)

    def _check_consistency(self, order: DishOrder) -> None:
        """Every robot is at exactly one zone; nothing of the order is left."""
        facts = self.knowledge.get_predicates()
        for robot in self.robots:
            places = [f for f in facts if f.predicate == "robot_at" and f.args[0] == robot]
            if len(places) != 1:
                self.stats.consistency_errors.append(
                    f"mission {order.number}: {robot} is at {len(places)} zones"
                )
        leftovers = [f for f in facts if any(a in order.instances for a in f.args)]
        if leftovers:
            self.stats.consistency_errors.append(
                f"mission {order.number}: leftovers {leftovers[:3]}"
            )

    async def _battery_drops(self) -> None:
        rate = self.config.battery_drops_per_hour * len(self.robots) / 3600.0
        if rate <= 0:
            return
        while True:
            await self.clock.sleep(self.rng.expovariate(rate))
            robot = self.rng.choice(self.robots)
            try:
                if self.knowledge.remove_predicate(f"(battery_full {robot})"):
                    self.stats.battery_drops += 1
            except PlansysBridgeError:
                continue

    async def _unresponsive(self) -> None:
        rate = self.config.unresponsive_per_hour / 3600.0
        if rate <= 0:
            return
        while True:
            await self.clock.sleep(self.rng.expovariate(rate))
            performer = self.rng.choice(self.performers)
            performer.set_unresponsive(True)
            self.stats.unresponsive_injected += 1
            asyncio.get_running_loop().call_later(
                self.config.unresponsive_for * self.clock.time_scale,
                performer.set_unresponsive,
                False,
            )
