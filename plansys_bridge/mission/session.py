"""A started mission: its hub, performers, knowledge publishing, events, recorder.

Shared by ``run``, ``serve``, the terminal and the replay, so every way of running
a mission starts and stops the same things in the same order.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Any

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.clock import Clock
from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import Topics
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.mission.file_keys import in_mission_file
from plansys_bridge.mission.knowledge import apply_event
from plansys_bridge.mission.transport import make_transport
from plansys_bridge.mission_config import EventConfig, MissionConfig
from plansys_bridge.monitoring.watch import MissionWatch
from plansys_bridge.pddl.model import Domain
from plansys_bridge.performers.base import ActionPerformer, PerformerContext
from plansys_bridge.performers.bid_costs import BidCosts, load_bid_costs
from plansys_bridge.performers.registry import performers_from_config, start_performers

__all__ = ["MissionSession", "Printer", "mission_bid_costs"]


def mission_bid_costs(mission: MissionConfig) -> dict[str, BidCosts]:
    """The learned costs the mission's ``bid_costs:`` names, by performer."""
    if mission.bid_costs is None:
        return {}
    return load_bid_costs(mission.resolve(mission.bid_costs))


log = logging.getLogger(__name__)

Printer = Callable[[str], None]


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
        await_performers: bool = True,
        watch: MissionWatch | None = None,
    ) -> None:
        self.mission = mission
        self.domain = domain
        self.knowledge = knowledge
        self.plan_ids: set[str] = set()
        """The plans this process executes (request ids start with one of them)."""
        self.hub = Hub(make_transport(mission, domain, plan_ids=self.plan_ids), clock)
        self.local_performers = local_performers
        """False: the performers run in other processes (DDS); wait for their heartbeats
        (unless ``await_performers`` is False: ``check actors`` lists whoever is alive)."""
        self.await_performers = await_performers
        self.watch = watch
        """Attached to the hub before the performers start, so it sees them all (the
        caller closes it)."""
        self.out = out
        self.performers: list[ActionPerformer] = []
        self.recorder: Any = None
        self.events_applied: list[str] = []
        self._overrides = performer_overrides or {}
        self._tasks: list[asyncio.Task[None]] = []
        self._unsubscribe: Callable[[], None] | None = None
        self.bridge: Any = None
        self.sensing: Any = None

    async def __aenter__(self) -> MissionSession:
        await self.hub.start()
        if self.watch is not None:
            self.watch.attach(self.hub)
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
                bid_costs=mission_bid_costs(self.mission),
            )
            entries = [p.model_dump() | self._overrides for p in self.mission.performers]
            if self.mission.bridge is not None:
                await self._start_bridge()
            if self.local_performers:
                with in_mission_file(self.mission):
                    self.performers = performers_from_config(entries, context)
            await start_performers(self.performers, self._say)
            if not self.local_performers and self.await_performers:
                await self._wait_for_remote_performers()
            self.hub.publish(Topics.KNOWLEDGE, self.knowledge.to_msg())
            self._unsubscribe = self.knowledge.subscribe(
                lambda _change: self.hub.publish(Topics.KNOWLEDGE, self.knowledge.to_msg())
            )
            if self.mission.sensing:
                from plansys_bridge.sensing.engine import start_sensing

                self.sensing = start_sensing(
                    self.mission,
                    self.knowledge,
                    self.hub.clock,
                    self.performers,
                    self._say,
                    self.events_applied,
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
            self.hub,
            names,
            timeout=self.mission.transport_kind().peer_timeout,
            where=self.mission.source,
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
        await cancel_and_wait(*self._tasks)
        if self.sensing is not None:
            self.sensing.stop()
            self.sensing = None
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
            text = apply_event(self.knowledge, event)
        except PlansysBridgeError as exc:
            self._say(f"[{event.at:8.1f}] event refused: {exc}")
            return
        self.events_applied.append(f"t={event.at:g} {text}")
        self._say(f"[{event.at:8.1f}] event: {text}")

    def _say(self, text: str) -> None:
        if self.out is not None:
            self.out(text)
