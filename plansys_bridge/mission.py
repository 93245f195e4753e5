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
import logging
import secrets
from collections.abc import Callable, Iterator, Mapping, Set
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from plansys_bridge.clock import Clock, VirtualClock, WallClock, run
from plansys_bridge.errors import ConfigError, PddlError, PlansysBridgeError
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.results import ExecutionResult, efficiency_text
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionStatus, Topics
from plansys_bridge.hub.transport import InProcessTransport, Transport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.mission_config import EventConfig, MissionConfig, make_planner
from plansys_bridge.monitoring.live import make_live_view
from plansys_bridge.monitoring.progress import ProgressLines
from plansys_bridge.monitoring.watch import MissionWatch
from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import ActionPerformer, PerformerContext
from plansys_bridge.performers.registry import (
    performers_from_config,
    start_performers,
    unserved_actions,
)
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.planner import Planner
from plansys_bridge.textfile import TextFileError, read_text

__all__ = [
    "MissionReport",
    "MissionSession",
    "build_knowledge",
    "in_mission_file",
    "make_clock",
    "make_transport",
    "run_mission",
]

log = logging.getLogger(__name__)

Printer = Callable[[str], None]


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


def make_clock(mission: MissionConfig) -> Clock:
    if mission.clock.kind == "virtual":
        return VirtualClock()
    return WallClock(time_scale=mission.clock.time_scale)


def make_transport(
    mission: MissionConfig,
    domain: Domain | None = None,
    role: str = "executor",
    plan_ids: Set[str] | None = None,
) -> Transport:
    """The hub transport the mission's ``transport:`` names (DDS imported only then),
    signed with the fleet key when ``auth:`` gives one (:mod:`plansys_bridge.hub.auth`).

    With ``domain``, a DDS transport drops received messages about actions the domain
    does not have (:func:`~plansys_bridge.hub.dds_checks.domain_check`), and with
    ``plan_ids`` (filled as plans start) those about a plan this process does not
    execute. Over DDS the
    process shows to ROS 2 tools as the node ``<mission name>_<role>``.
    """
    transport = _bare_transport(mission, domain, role, plan_ids)
    if mission.auth is None:
        return transport
    from plansys_bridge.hub.auth import AuthTransport, load_key

    with _keyed(mission, "auth.key_file"):
        key = load_key(mission.resolve(mission.auth.key_file))
    return AuthTransport(transport, key, window=mission.auth.window)


def _bare_transport(
    mission: MissionConfig, domain: Domain | None, role: str, plan_ids: Set[str] | None
) -> Transport:
    if mission.transport.kind == "dds":
        try:
            from plansys_bridge.hub.dds import DdsTransport
            from plansys_bridge.hub.dds_checks import domain_check
        except ImportError as exc:
            raise ConfigError(
                f"the dds transport needs cyclonedds (pip install plansys-bridge[dds]): {exc}",
                key="transport.kind",
                file=mission.source,
            ) from exc
        check = None
        if domain is not None:
            actions = {a.name: len(a.parameters) for a in domain.actions}
            check = domain_check(actions, plan_ids)
        return DdsTransport(
            mission.transport.domain_id,
            config=_dds_config(mission),
            check=check,
            node_name=f"{mission.name}_{role}",
        )
    return InProcessTransport()


def load_domain(mission: MissionConfig) -> Domain:
    """The mission's domain files, parsed and merged; a file that cannot be read is
    an error naming the mission file and its ``domain`` entry."""
    paths = mission.domain_paths
    try:
        return parse_domain_files(paths)
    except PddlError as exc:
        cause = exc.__cause__
        if not isinstance(cause, TextFileError):
            raise
        i = next((i for i, p in enumerate(paths) if str(p) == cause.path), 0)
        key = "domain" if len(paths) == 1 else f"domain[{i}]"
        raise ConfigError(str(cause), key=key, file=mission.source) from exc


def _dds_config(mission: MissionConfig) -> str:
    """The Cyclone XML for the mission's ``transport:`` (loopback unless configured)."""
    from plansys_bridge.hub.dds_config import network_config

    t = mission.transport
    if t.config is not None:
        try:
            return read_text(mission.resolve(t.config), "Cyclone DDS XML")
        except PlansysBridgeError as exc:
            raise ConfigError(str(exc), key="transport.config", file=mission.source) from exc
    try:
        return network_config(
            t.domain_id, interfaces=t.interfaces, peers=t.peer_list(), multicast=t.multicast
        )
    except ConfigError as exc:
        raise ConfigError(
            str(exc).split(": ", 1)[-1], key=f"transport.{exc.key}", file=mission.source
        ) from exc


def build_knowledge(mission: MissionConfig, domain: Domain) -> ProblemExpert:
    """The problem expert with the mission's problem file and inline knowledge.

    All of it goes in one transaction: a bad entry leaves nothing half-loaded, and
    the error names the entry's key in the mission file. The mission's other
    references to the domain and the knowledge are checked here too, before anything
    starts: each performer's actions must be actions of the domain, and each timed
    event must be a change the knowledge would accept (it is tried, then undone).
    """
    knowledge = ProblemExpert(domain)
    with knowledge.transaction():
        if mission.problem is not None:
            path = mission.resolve(mission.problem)
            with _keyed(mission, "problem"):
                knowledge.load_problem(read_text(path, "problem file"), filename=str(path))
        for name, type_name in mission.knowledge.instances.items():
            with _keyed(mission, f"knowledge.instances.{name}"):
                knowledge.add_instance(name, type_name)
        for i, fact in enumerate(mission.knowledge.predicates):
            with _keyed(mission, f"knowledge.predicates[{i}]"):
                knowledge.add_predicate(fact)
        for i, value in enumerate(mission.knowledge.functions):
            with _keyed(mission, f"knowledge.functions[{i}]"):
                knowledge.set_function(value)
        if mission.goal is not None:
            with _keyed(mission, "goal"):
                knowledge.set_goal(mission.goal)
        _check_performer_actions(mission, knowledge)
        _rehearse_events(mission, knowledge)
    return knowledge


def _check_performer_actions(mission: MissionConfig, knowledge: ProblemExpert) -> None:
    """A performer offering an action the domain lacks, or specialised to an object
    the mission does not have, is a typo, not a capability: it never bids, and the
    action it was meant for finds no performer."""
    domain = knowledge.domain
    known = {a.name for a in domain.actions}
    objects = set(knowledge.get_instances()) | {c.name for c in domain.constants}
    for i, entry in enumerate(mission.performers):
        actions = getattr(entry, "actions", None)
        specs = actions if isinstance(actions, Mapping) else {}
        names = list(actions) if isinstance(actions, Mapping | list | tuple) else []
        for name in names:
            if not isinstance(name, str):
                continue
            where = f"performers[{i}].actions.{name}"
            if name.strip().lower() not in known:
                raise ConfigError(
                    f"domain {domain.name} has no action {name!r} "
                    f"(its actions: {', '.join(sorted(known)) or 'none'})",
                    key=where,
                    file=mission.source,
                )
            spec = specs.get(name)
            for j, arg in enumerate(spec if isinstance(spec, list | tuple) else ()):
                if isinstance(arg, str) and arg.strip() and arg.strip().lower() not in objects:
                    raise ConfigError(
                        f"no object {arg!r} in the mission's knowledge or the domain's constants",
                        key=f"{where}[{j}]",
                        file=mission.source,
                    )


class _Rehearsed(Exception):
    """Ends the trial run of the events so that the transaction undoes it."""


def _rehearse_events(mission: MissionConfig, knowledge: ProblemExpert) -> None:
    """Apply every timed event now and undo them: one the knowledge would refuse at
    its time (unknown object or predicate, a typo) is an error at load instead."""
    if not mission.events:
        return
    try:
        with knowledge.transaction():
            for i, event in enumerate(mission.events):
                with _keyed(mission, f"events[{i}].{_event_key(event)}"):
                    _apply_event(knowledge, event)
            raise _Rehearsed
    except _Rehearsed:
        pass


def _event_key(event: EventConfig) -> str:
    return next(
        k for k in ("add_predicate", "remove_predicate", "set_function") if getattr(event, k)
    )


def _apply_event(knowledge: ProblemExpert, event: EventConfig) -> str:
    """Make the event's change; returns it as text (``+(p a)``, ``-(p a)``, ``(= (f) 1)``)."""
    if event.add_predicate:
        knowledge.add_predicate(event.add_predicate)
        return f"+{event.add_predicate}"
    if event.remove_predicate:
        knowledge.remove_predicate(event.remove_predicate)
        return f"-{event.remove_predicate}"
    knowledge.set_function(event.set_function or "")
    return f"{event.set_function}"


@contextlib.contextmanager
def in_mission_file(mission: MissionConfig) -> Iterator[None]:
    """Add the mission file's name to a ConfigError that names only the key (the
    performer plugins check their settings knowing the key, not the file)."""
    try:
        yield
    except ConfigError as exc:
        if exc.file is not None:
            raise
        message = str(exc).removeprefix(f"{exc.key}: ") if exc.key else str(exc)
        raise ConfigError(message, key=exc.key, file=mission.source) from exc


@contextlib.contextmanager
def _keyed(mission: MissionConfig, key: str) -> Iterator[None]:
    """Turn a refused change into a ConfigError naming the mission file's key."""
    try:
        yield
    except PlansysBridgeError as exc:
        raise ConfigError(str(exc), key=key, file=mission.source) from exc


class MissionSession:
    """A hub with its performers, knowledge publishing, events and recorder, started.

    Used as ``async with MissionSession(...) as session:`` so that performers are
    stopped, the recorder flushed and the hub closed whatever happens.
    """

    def __init__(
        self,
        mission: MissionConfig,
        domain: Domain,
        knowledge: ProblemExpert,
        clock: Clock,
        *,
        out: Printer | None = None,
        performer_overrides: dict[str, Any] | None = None,
        local_performers: bool = True,
    ) -> None:
        self.mission = mission
        self.domain = domain
        self.knowledge = knowledge
        self.plan_ids: set[str] = set()
        """The plans this process executes (request ids start with one of them)."""
        self.hub = Hub(make_transport(mission, domain, plan_ids=self.plan_ids), clock)
        self.local_performers = local_performers
        """False: the performers run in other processes (DDS); wait for their heartbeats."""
        self.out = out
        self.performers: list[ActionPerformer] = []
        self.recorder: Any = None
        self.events_applied: list[str] = []
        self._overrides = performer_overrides or {}
        self._tasks: list[asyncio.Task[None]] = []
        self._unsubscribe: Callable[[], None] | None = None
        self.bridge: Any = None

    async def __aenter__(self) -> MissionSession:
        await self.hub.start()
        try:
            if self.mission.record:
                from plansys_bridge.monitoring.recorder import MissionRecorder

                self.recorder = MissionRecorder(
                    self.hub, self.mission.resolve(self.mission.record)
                ).start()
            context = PerformerContext(
                hub=self.hub,
                clock=self.hub.clock,
                knowledge=self.knowledge,
                base_dir=self.mission.base_dir,
                recorder=self.recorder,
            )
            entries = [p.model_dump() | self._overrides for p in self.mission.performers]
            if self.mission.bridge is not None:
                await self._start_bridge()
            if self.local_performers:
                with in_mission_file(self.mission):
                    self.performers = performers_from_config(entries, context)
            await start_performers(self.performers, self._say)
            if not self.local_performers:
                await self._wait_for_remote_performers()
            self.hub.publish(Topics.KNOWLEDGE, self.knowledge.to_msg())
            self._unsubscribe = self.knowledge.subscribe(
                lambda _change: self.hub.publish(Topics.KNOWLEDGE, self.knowledge.to_msg())
            )
            loop = asyncio.get_running_loop()
            for event in self.mission.events:
                self._tasks.append(loop.create_task(self._event(event)))
        except BaseException:
            await self._shutdown()
            raise
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self._shutdown()

    async def _wait_for_remote_performers(self) -> None:
        from plansys_bridge.performers.remote import wait_for_performers

        names = [p.name for p in self.mission.performers]
        self._say(f"waiting for performers {', '.join(names)} (dds)")
        await wait_for_performers(
            self.hub, names, timeout=self.mission.transport.peer_timeout, where=self.mission.source
        )

    async def _start_bridge(self) -> None:
        from plansys_bridge.bridge.bridge import Bridge
        from plansys_bridge.bridge.config import parse_bridge_config

        config = parse_bridge_config(
            self.mission.bridge, source=self.mission.source or "", key="bridge"
        )
        self.bridge = Bridge(config)
        await self.bridge.start()
        self._say(f"bridge: {len(config.routes)} topics between ROS 1 and ROS 2")

    async def _shutdown(self) -> None:
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        if self._unsubscribe is not None:
            self._unsubscribe()
        for performer in reversed(self.performers):
            try:
                await performer.stop()
            except Exception:  # a broken adapter must not keep the others running
                log.exception("stopping performer %s failed", performer.node_name)
        if self.bridge is not None:
            await self.bridge.stop()
            self.bridge = None
        if self.recorder is not None:
            self.recorder.close()
        await self.hub.close()

    async def _event(self, event: EventConfig) -> None:
        await self.hub.clock.sleep(event.at)
        self.apply_event(event)

    def apply_event(self, event: EventConfig) -> None:
        try:
            text = _apply_event(self.knowledge, event)
        except PlansysBridgeError as exc:
            self._say(f"[{event.at:8.1f}] event refused: {exc}")
            return
        self.events_applied.append(f"t={event.at:g} {text}")
        self._say(f"[{event.at:8.1f}] event: {text}")

    def _say(self, text: str) -> None:
        if self.out is not None:
            self.out(text)


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
    if not local_performers and mission.transport.kind != "dds":
        raise ConfigError(
            "performers in other processes need transport: {kind: dds}",
            key="transport.kind",
            file=mission.source,
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
    async with MissionSession(
        mission, domain, knowledge, clock, out=say, local_performers=local_performers
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
        view = make_live_view(elapsed, mission.name) if live and out is not None else None
        listener = view if view is not None else ProgressLines(say, elapsed)
        watch = MissionWatch(clock.now, listener).attach(session.hub)
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
    packaged = Path(__file__).resolve().parent / "data" / "configs"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[1] / "configs"
