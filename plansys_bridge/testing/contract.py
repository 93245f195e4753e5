"""The contract every action performer keeps, as tests an adapter package inherits.

Subclass :class:`PerformerContract` in a test module and describe your performer with
a mission-file entry and an action call it can complete; pytest collects the
``test_contract_*`` methods and runs each against a fresh performer built through
the entry point (``from_config``), on the in-process hub and, by default, the
virtual clock::

    class TestGripper(PerformerContract):
        entry = {"kind": "gripper", "name": "g1", "actions": {"grasp": ["g1"]}}
        goal = ("grasp", ("g1", "cup"))
        failing_goal = ("grasp", ("g1", "anvil"))          # optional
        bad_settings = [({"force": -1}, "force")]          # optional: change, key

What is checked: the kind is registered under the performers entry-point group; the
heartbeat says READY while idle and NOT_READY after stop; the performer answers an
auction only for an action it offers with matching specialised arguments; a goal
sends FEEDBACK and exactly one FINISH; a CANCEL is honoured within
``cancel_within`` seconds of mission time; a failure says why; bad settings are a
ConfigError naming the key.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any, ClassVar

import pytest

from plansys_bridge.clock import Clock, VirtualClock, run
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionPerformerStatus,
    ExecutionType,
    PerformerState,
    Topics,
)
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionPerformer, PerformerContext
from plansys_bridge.performers.registry import load_performer_kind

__all__ = ["PerformerContract"]

Call = tuple[str, tuple[str, ...]]


class PerformerContract:
    """Inherit to run the performer contract; set the class attributes below."""

    entry: ClassVar[dict[str, Any]] = {}
    """A mission-file performer entry (kind, name, actions, kind settings)."""
    goal: ClassVar[Call] = ("", ())
    """An action call the performer completes: ``("move", ("r1", "a", "b"))``."""
    failing_goal: ClassVar[Call | None] = None
    """An action call it fails (with a reason), if it has one."""
    bad_settings: ClassVar[list[tuple[dict[str, Any], str]]] = []
    """Changes to ``entry`` that are configuration errors, with the key each names
    (``""``: the entry as a whole, as ``from_config`` reports an ``__init__`` error)."""
    cancel_within: ClassVar[float] = 5.0
    """Seconds (mission time) from CANCEL until the performer is idle again."""
    action_timeout: ClassVar[float] = 600.0
    """Seconds (mission time) the goal may take."""
    ready_within: ClassVar[float] = 30.0
    """Seconds (mission time) from start until the performer says READY (a link to
    open, a peer to find)."""

    # ------------------------------------------------------------ hooks

    def make_clock(self) -> Clock:
        """The clock of each test; override for adapters that need the wall clock."""
        return VirtualClock()

    def make_context(self, hub: Hub) -> PerformerContext:
        """What the performer is built with; override to give knowledge or a base_dir."""
        return PerformerContext(hub=hub, clock=hub.clock)

    def build(self, context: PerformerContext, entry: dict[str, Any]) -> ActionPerformer:
        kind = load_performer_kind(entry["kind"])
        [performer] = kind.from_config(entry, context, key="performer")
        return performer

    # ------------------------------------------------------------ harness

    def _run(self, body: Callable[[Hub, ActionPerformer], Awaitable[None]]) -> None:
        clock = self.make_clock()

        async def main() -> None:
            hub = Hub(InProcessTransport(), clock)
            await hub.start()
            try:
                performer = self.build(self.make_context(hub), dict(self.entry))
                try:
                    await body(hub, performer)
                finally:
                    await performer.stop()
            finally:
                await hub.close()

        run(main(), clock)

    async def _until(self, hub: Hub, done: Callable[[], bool], limit: float) -> bool:
        """Wait (mission time) until ``done()``; False when ``limit`` passed first."""
        end = hub.clock.now() + limit
        while not done():
            if hub.clock.now() >= end:
                return False
            await hub.clock.sleep(0.01)
        return True

    async def _start(self, hub: Hub, performer: ActionPerformer) -> None:
        """Start the performer and wait until its heartbeat says READY."""
        await performer.start()
        ready = await self._until(
            hub, lambda: performer.state == PerformerState.READY, self.ready_within
        )
        assert ready, f"{performer.node_name} not READY {self.ready_within} s after start"

    # ------------------------------------------------------------ the contract

    def test_contract_kind_is_registered(self) -> None:
        cls = load_performer_kind(self.entry["kind"])
        assert issubclass(cls, ActionPerformer)

    def test_contract_heartbeat_and_states(self) -> None:
        async def body(hub: Hub, performer: ActionPerformer) -> None:
            states: list[PerformerState] = []

            def on_status(msg: object) -> None:
                if isinstance(msg, ActionPerformerStatus) and msg.node_name == performer.node_name:
                    states.append(PerformerState(msg.state))

            sub = hub.subscribe(Topics.PERFORMERS_STATUS, on_status)
            await self._start(hub, performer)
            await hub.clock.sleep(performer.heartbeat_period * 3.5)
            assert states.count(PerformerState.READY) >= 3, f"heartbeats: {states}"
            await performer.stop()
            await hub.clock.sleep(0.05)
            sub.close()
            assert states[-1] == PerformerState.NOT_READY, f"after stop: {states}"

        self._run(body)

    def test_contract_bids_only_for_offered_actions(self) -> None:
        async def body(hub: Hub, performer: ActionPerformer) -> None:
            answers: list[ActionExecution] = []

            def on_msg(msg: object) -> None:
                if (
                    isinstance(msg, ActionExecution)
                    and msg.type == ExecutionType.RESPONSE
                    and msg.node_id == performer.node_name
                ):
                    answers.append(msg)

            sub = hub.subscribe(Topics.ACTIONS_HUB, on_msg)
            await self._start(hub, performer)
            action, args = self.goal
            asks = [("not_offered_action_x", args, "unoffered")]
            spec = performer.actions.get(action, ())
            for i, value in enumerate(spec):
                if value and i < len(args):
                    other = (*args[:i], f"{value}_other", *args[i + 1 :])
                    asks.append((action, other, f"specialised-{i}"))
            asks.append((action, args, "offered"))
            for name, arguments, request_id in asks:
                hub.publish(
                    Topics.ACTIONS_HUB,
                    ActionExecution(
                        ExecutionType.REQUEST, "", name, arguments, request_id=request_id
                    ),
                )
                await hub.clock.sleep(0.5)
            sub.close()
            answered = [a.request_id for a in answers]
            assert answered == ["offered"], f"answered {answered}, expected only 'offered'"
            hub.publish(
                Topics.ACTIONS_HUB,
                ActionExecution(
                    ExecutionType.REJECT, performer.node_name, action, args, request_id="offered"
                ),
            )

        self._run(body)

    def test_contract_feedback_and_one_finish(self) -> None:
        async def body(hub: Hub, performer: ActionPerformer) -> None:
            seen: list[ActionExecution] = []
            sub = hub.subscribe(Topics.ACTIONS_HUB, _collect(seen, performer.node_name))
            await self._start(hub, performer)
            client = ActionClient(hub, *self.goal)
            outcome = await asyncio.wait_for(client.run(), self.action_timeout)
            await hub.clock.sleep(1.0)
            sub.close()
            assert outcome.success, outcome.status
            mine = [m for m in seen if m.request_id == client.request_id]
            kinds = [ExecutionType(m.type) for m in mine]
            assert kinds.count(ExecutionType.FINISH) == 1, kinds
            assert ExecutionType.FEEDBACK in kinds, f"no FEEDBACK: {kinds}"
            assert kinds.index(ExecutionType.FEEDBACK) < kinds.index(ExecutionType.FINISH)
            assert await self._until(hub, lambda: not performer.busy, 1.0)

        self._run(body)

    def test_contract_cancel_is_honoured(self) -> None:
        async def body(hub: Hub, performer: ActionPerformer) -> None:
            await self._start(hub, performer)
            client = ActionClient(hub, *self.goal)
            task = asyncio.ensure_future(client.run())
            started = await self._until(hub, lambda: performer.busy, self.action_timeout)
            assert started, "the goal never started"
            cancelled_at = hub.clock.now()
            client.cancel()
            outcome = await asyncio.wait_for(task, self.cancel_within + 5.0)
            idle = await self._until(hub, lambda: not performer.busy, self.cancel_within)
            took = hub.clock.now() - cancelled_at
            assert idle, f"still busy {took:.2f} s after CANCEL"
            assert outcome.cancelled and not outcome.success, outcome
            assert performer.state == PerformerState.READY, performer.state

        self._run(body)

    def test_contract_failure_says_why(self) -> None:
        if self.failing_goal is None:
            pytest.skip("no failing_goal declared")
        failing = self.failing_goal

        async def body(hub: Hub, performer: ActionPerformer) -> None:
            await self._start(hub, performer)
            outcome = await asyncio.wait_for(ActionClient(hub, *failing).run(), self.action_timeout)
            assert not outcome.success
            assert outcome.status.strip(), "a failure must say why"

        self._run(body)

    def test_contract_settings_errors_name_the_key(self) -> None:
        if not self.bad_settings:
            pytest.skip("no bad_settings declared")
        clock = self.make_clock()
        for change, key in self.bad_settings:
            hub = Hub(InProcessTransport(), clock)
            entry = {k: v for k, v in {**self.entry, **change}.items() if v is not None}
            with pytest.raises(ConfigError) as err:
                self.build(self.make_context(hub), entry)
            expected = f"performer.{key}" if key else "performer"
            assert err.value.key == expected, str(err.value)


def _collect(into: list[ActionExecution], node: str) -> Callable[[object], None]:
    def on_msg(msg: object) -> None:
        if isinstance(msg, ActionExecution) and msg.node_id == node:
            into.append(msg)

    return on_msg
