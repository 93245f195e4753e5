"""Run a mission file: knowledge in, plan, performers, execution, summary out.

This is what ``plansys-bridge run CONFIG.yaml`` does, and what the demo, the
adapters' example configs and the end-to-end tests go through, so there is one
way to start a mission. Everything a run needs is built from the validated
:class:`~plansys_bridge.mission_config.MissionConfig`; performer kinds are found
through the ``plansys_bridge.performers`` entry points only.
"""

from __future__ import annotations

import asyncio
import contextlib
import secrets
from dataclasses import dataclass, field
from pathlib import Path

from plansys_bridge.clock import Clock, run
from plansys_bridge.errors import ConfigError, PlansysBridgeError
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.results import ExecutionResult, efficiency_text
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.mission.file_keys import in_mission_file
from plansys_bridge.mission.knowledge import build_knowledge, load_domain
from plansys_bridge.mission.session import MissionSession, Printer
from plansys_bridge.mission.transport import make_clock
from plansys_bridge.mission_config import MissionConfig, make_planner
from plansys_bridge.monitoring.live import make_live_view
from plansys_bridge.monitoring.progress import ProgressLines
from plansys_bridge.monitoring.watch import MissionWatch
from plansys_bridge.pddl.model import Domain
from plansys_bridge.performers.registry import unserved_actions
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.planner import Planner

__all__ = ["MissionReport", "default_missions_dir", "plan_now", "run_mission"]


@dataclass
class MissionReport:
    """What a mission run ends with; ``result`` holds every action's record."""

    name: str
    success: bool
    status: str
    message: str
    result: ExecutionResult | None
    planning_s: float = 0.0
    events_applied: list[str] = field(default_factory=list)
    watch: MissionWatch | None = None
    """What went over the hub during the execution (for pictures, ``--report``)."""

    def summary(self) -> str:
        r = self.result
        lines = [
            f"mission {self.name}: {self.status.upper()}"
            + (f" ({self.message})" if self.message else "")
        ]
        if r is not None:
            done = sum(1 for a in r.actions if a.status == ActionStatus.SUCCEEDED)
            lines += [
                f"  plans: {len(r.plans)} (replans: {r.replans})",
                f"  actions: {done} succeeded, {r.failures} failed or halted,"
                f" {len(r.actions)} planned",
                f"  mission time: {r.total_time:.1f} s, planning: {self.planning_s:.3f} s",
                f"  efficiency: {efficiency_text(r)} (action time / total time)",
            ]
        if self.events_applied:
            lines.append(f"  events: {'; '.join(self.events_applied)}")
        return "\n".join(lines)


async def plan_now(
    planner: Planner, domain: Domain, knowledge: ProblemExpert
) -> tuple[Plan, float]:
    """Plan from the current knowledge in a worker thread; PlanningError when none."""
    from plansys_bridge.errors import PlanningError

    problem = knowledge.to_problem()
    result = await asyncio.to_thread(planner.solve, domain, problem)
    if result.plan is None:
        raise PlanningError(
            f"no plan ({result.status.name.lower()}, {result.solver}): {result.message}"
        )
    return result.plan, result.elapsed_s


def run_mission(
    mission: MissionConfig,
    *,
    out: Printer | None = print,
    planner: Planner | None = None,
    plan: Plan | None = None,
    local_performers: bool = True,
    live: bool = False,
) -> MissionReport:
    """Run ``mission`` to its end on the clock it names; prints progress to ``out``.

    ``local_performers=False`` runs the executor only: the performers are served by
    ``plansys-bridge performers`` in other processes over the DDS transport.
    ``live=True`` shows progress as a table redrawn in place (rich, for a terminal)
    instead of one line per change.
    """
    with in_mission_file(mission):
        return _run_mission(mission, out, planner, plan, local_performers, live)


def _run_mission(
    mission: MissionConfig,
    out: Printer | None,
    planner: Planner | None,
    plan: Plan | None,
    local_performers: bool,
    live: bool,
) -> MissionReport:
    domain = load_domain(mission)
    knowledge = build_knowledge(mission, domain)
    if knowledge.get_goal() is None:
        raise ConfigError(
            "the mission has no goal (neither in the problem nor as goal:)",
            key="goal",
            file=mission.source,
        )
    clock = make_clock(mission)
    planner = planner or make_planner(mission)
    if not local_performers and not mission.transport_kind().distributed:
        raise mission.error(
            "performers in other processes need a transport between processes "
            "(transport: {kind: dds})",
            key="transport.kind",
        )
    return run(
        _run(mission, domain, knowledge, clock, planner, plan, out, local_performers, live), clock
    )


async def _run(
    mission: MissionConfig,
    domain: Domain,
    knowledge: ProblemExpert,
    clock: Clock,
    planner: Planner,
    plan: Plan | None,
    out: Printer | None,
    local_performers: bool = True,
    live: bool = False,
) -> MissionReport:
    t0 = clock.now()

    def elapsed() -> float:
        return clock.now() - t0

    say = out or (lambda _s: None)
    view = make_live_view(elapsed, mission.name) if live and out is not None else None
    watch = MissionWatch(clock.now, view if view is not None else ProgressLines(say, elapsed))
    async with MissionSession(
        mission, domain, knowledge, clock, out=say, local_performers=local_performers, watch=watch
    ) as session:
        performers = (
            f"{len(session.performers)} performers"
            if local_performers
            else f"{len(mission.performers)} remote performers"
        )
        say(f"mission {mission.name}: {performers}, clock {mission.clock.kind}")
        planning_s = 0.0
        if plan is None:
            try:
                plan, planning_s = await plan_now(planner, domain, knowledge)
            except PlansysBridgeError as exc:
                return MissionReport(
                    mission.name,
                    False,
                    "no plan",
                    str(exc),
                    None,
                    events_applied=session.events_applied,
                )
        say(
            f"plan ({len(plan)} actions, makespan {plan.makespan:.1f} s,"
            f" planned in {planning_s:.3f} s):"
        )
        for line in plan.to_text().splitlines():
            say(f"    {line}")
        missing = unserved_actions(((s.action, s.arguments) for s in plan), session.performers)
        if local_performers and missing:
            return MissionReport(
                mission.name,
                False,
                "no performer",
                f"{mission.source}: no performer offers {', '.join(missing)} "
                "(add it to a performer's actions, or check their specialised arguments)",
                None,
                planning_s,
                session.events_applied,
            )
        executor = Executor(session.hub, domain, knowledge, planner, mission.executor_options())
        plan_id = f"{mission.name}-{secrets.token_hex(4)}"
        session.plan_ids.add(plan_id)  # DDS: messages naming another plan are dropped
        execute = executor.execute(plan, goal=knowledge.get_goal(), plan_id=plan_id)
        try:
            with view if view is not None else contextlib.nullcontext():
                if view is not None:
                    view.bind(watch)
                result = await (
                    asyncio.wait_for(execute, mission.timeout) if mission.timeout else execute
                )
                await _heard_the_end(watch, result)
        except TimeoutError:
            watch.close()
            return MissionReport(
                mission.name,
                False,
                "timeout",
                f"not done after {mission.timeout} s",
                None,
                planning_s,
                session.events_applied,
                watch,
            )
        watch.close()
        return MissionReport(
            mission.name,
            result.success,
            result.status,
            result.message,
            result,
            planning_s,
            list(session.events_applied),
            watch,
        )


async def _heard_the_end(watch: MissionWatch, result: ExecutionResult, wait: float = 2.0) -> None:
    """Let the plan's last messages reach the watch before it closes.

    In-process they are one loop turn away; over DDS a process hears its own
    messages back through the network, so wait (``wait`` seconds at most) until the
    watch saw every action's final status, or the last lines (a failure and why)
    would go unprinted."""
    await asyncio.sleep(0)
    final = (ActionStatus.SUCCEEDED, ActionStatus.FAILED, ActionStatus.CANCELLED)
    want = {(r.text, r.status) for r in result.actions if r.status in final}
    loop = asyncio.get_running_loop()
    deadline = loop.time() + wait
    while loop.time() < deadline and not want <= {(a.text, a.status) for a in watch.actions}:
        await asyncio.sleep(0.01)


def default_missions_dir() -> Path:
    """The example missions: shipped in the package (a wheel), else the checkout's configs/."""
    packaged = Path(__file__).resolve().parents[1] / "data" / "configs"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[2] / "configs"
