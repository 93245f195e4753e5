"""Run the terminal's plans with a mission's performers, clock and hub.

Each ``run`` opens the mission's hub, starts its performers (unless they are
served by other processes over DDS: ``local_performers=False``), executes and
stops them; the mission's timed events are not replayed (the operator drives the
knowledge). Progress is shown as ``plansys-bridge run`` shows it: a live table
(rich) on a terminal, one line per change otherwise.

``check actors`` opens the hub the same way and lists every performer whose
heartbeat it hears, as PlanSys2's terminal does: the mission's own and, on a DDS
hub, those of any other process on the domain. It listens for two seconds of the
time heartbeats are sent on: real seconds on the wall clock (whatever its time
scale), no wall time at all on the virtual clock.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from plansys_bridge.terminal.runner import Actor

if TYPE_CHECKING:
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.mission_config import MissionConfig
    from plansys_bridge.monitoring.watch import MissionWatch, PerformerView
    from plansys_bridge.planning.plan import Plan

__all__ = ["LISTEN_S", "MissionRunner"]

LISTEN_S = 2.0
"""How long ``check actors`` listens for heartbeats (loop seconds: real ones on the
wall clock, mission ones on the virtual clock)."""


class MissionRunner:
    """A :class:`~plansys_bridge.terminal.runner.Runner` over a mission file.

    ``out`` receives the progress lines; ``live=True`` draws the live table instead
    (on ``console``, a rich console, default: the standard output).
    """

    def __init__(
        self,
        mission: MissionConfig,
        knowledge: ProblemExpert,
        planner: Callable[[], Any],
        out: Callable[[str], None] | None = None,
        *,
        local_performers: bool = True,
        live: bool = False,
        console: Any = None,
    ) -> None:
        if not local_performers and not mission.transport_kind().distributed:
            raise mission.error(
                "performers in other processes need a transport between processes "
                "(transport: {kind: dds})",
                key="transport.kind",
            )
        self.mission = mission.model_copy(update={"events": []})
        self.knowledge = knowledge
        self.planner = planner
        self.out = out
        self.local_performers = local_performers
        self.live = live
        self.console = console

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
            # heartbeat periods are counted in loop time (real seconds on the wall
            # clock whatever its time scale), so the listening is too
            await asyncio.sleep(LISTEN_S)
            now = asyncio.get_running_loop().time()
            return [_actor(p, now) for p in watch.performers.values()]

        found: list[Actor] = self._in_session(listen, progress=False)
        return found

    def _in_session(self, body: Callable[[Any, MissionWatch], Any], *, progress: bool) -> Any:
        """Run ``body(session, watch)`` on the mission's hub, its performers started."""
        import contextlib

        from plansys_bridge.clock import run as run_on_clock
        from plansys_bridge.mission import MissionSession, make_clock
        from plansys_bridge.monitoring.watch import MissionWatch

        clock = make_clock(self.mission)
        t0 = clock.now()

        def elapsed() -> float:
            return clock.now() - t0

        listener, view = self._progress(elapsed) if progress else (None, None)

        async def go() -> Any:
            # progress is stamped in mission time; heartbeats (``check actors``) in
            # loop time, the time their period is counted in
            stamps = clock.now if progress else asyncio.get_running_loop().time
            watch = MissionWatch(stamps, listener)
            async with MissionSession(
                self.mission,
                self.knowledge.domain,
                self.knowledge,
                clock,
                local_performers=self.local_performers,
                await_performers=progress,
                watch=watch,
            ) as session:
                if view is not None:
                    view.bind(watch)
                with view if view is not None else contextlib.nullcontext():
                    try:
                        return await body(session, watch)
                    finally:
                        await asyncio.sleep(0)  # the last messages reach the watch
                        watch.close()

        return run_on_clock(go(), clock)

    def _progress(self, elapsed: Callable[[], float]) -> tuple[Any, Any]:
        """(watch listener, live view or None) for a run's progress."""
        from plansys_bridge.monitoring.live import LiveView, make_live_view
        from plansys_bridge.monitoring.progress import ProgressLines

        if self.live:
            view = (
                make_live_view(elapsed, self.mission.name)
                if self.console is None
                else LiveView(elapsed, title=self.mission.name, console=self.console)
            )
            if view is not None:
                return view, view
        if self.out is None:
            return None, None
        return ProgressLines(self.out, elapsed), None


def _actor(p: PerformerView, now: float) -> Actor:
    actions = sorted(f"{a} [{' '.join(args)}]" if args else a for a, args in p.actions.items())
    return Actor(p.name, p.state.name, tuple(actions), max(0.0, now - p.heard))
