"""Run the terminal's plans with a mission's performers, clock and hub.

Each ``run`` starts the mission's performers on a fresh hub, executes and stops
them (the mission's timed events are not replayed: the operator drives the
knowledge). Progress is printed live as ``plansys-bridge run`` prints it. ``check
actors`` starts the performers the same way and listens to their heartbeats for
two seconds of mission time, as PlanSys2's terminal does; on the virtual clock
that takes no wall time.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from plansys_bridge.terminal.runner import Actor

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.mission_config import MissionConfig
    from plansys_bridge.monitoring.watch import MissionWatch
    from plansys_bridge.planning.plan import Plan

__all__ = ["LISTEN_S", "MissionRunner"]

LISTEN_S = 2.0
"""How long ``check actors`` listens for heartbeats (mission seconds)."""


class MissionRunner:
    """A :class:`~plansys_bridge.terminal.runner.Runner` over a mission file."""

    def __init__(
        self,
        mission: MissionConfig,
        knowledge: ProblemExpert,
        planner: Callable[[], Any],
        out: Callable[[str], None] | None = None,
    ) -> None:
        self.mission = mission.model_copy(update={"events": []})
        self.knowledge = knowledge
        self.planner = planner
        self.out = out

    def execute(self, plan: Plan, *, to_goal: bool) -> str:
        from plansys_bridge.execution.executor import Executor

        async def go(session: Any, watch: MissionWatch) -> Any:
            executor = Executor(
                session.hub,
                self.knowledge.domain,
                self.knowledge,
                self.planner() if to_goal else None,
                self.mission.executor_options(),
            )
            goal = self.knowledge.get_goal() if to_goal else None
            return await executor.execute(plan, goal=goal)

        result = self._in_session(go, progress=True)
        headline = f"{result.status}: {result.message}".rstrip(": ")
        # a failed execution reads as an error, so scripts see it in the exit status
        lines = [headline if result.success else f"error: execution {headline}"]
        lines += [f"  {a.status.name:<9} {a.text}" for a in result.actions]
        return "\n".join(lines)

    def actors(self) -> list[Actor]:
        async def listen(session: Any, watch: MissionWatch) -> list[Actor]:
            await session.hub.clock.sleep(LISTEN_S)
            now = session.hub.clock.now()
            return [
                Actor(
                    p.name,
                    p.state.name,
                    tuple(
                        sorted(
                            f"{a} [{' '.join(args)}]" if args else a
                            for a, args in p.actions.items()
                        )
                    ),
                    max(0.0, now - p.last_seen),
                )
                for p in watch.performers.values()
            ]

        found: list[Actor] = self._in_session(listen, progress=False)
        return found

    def _in_session(self, body: Callable[[Any, MissionWatch], Any], *, progress: bool) -> Any:
        """Run ``body(session, watch)`` with the mission's performers started."""
        import asyncio

        from plansys_bridge.clock import run as run_on_clock
        from plansys_bridge.mission import MissionSession, make_clock
        from plansys_bridge.monitoring.progress import ProgressLines
        from plansys_bridge.monitoring.watch import MissionWatch

        clock = make_clock(self.mission)
        t0 = clock.now()
        listener = (
            ProgressLines(self.out, lambda: clock.now() - t0)
            if progress and self.out is not None
            else None
        )

        async def go() -> Any:
            async with MissionSession(
                self.mission, self.knowledge.domain, self.knowledge, clock
            ) as session:
                watch = MissionWatch(clock.now, listener).attach(session.hub)
                try:
                    return await body(session, watch)
                finally:
                    await asyncio.sleep(0)  # the last messages reach the watch
                    watch.close()

        return run_on_clock(go(), clock)
