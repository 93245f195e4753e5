"""The performer base class: matching, lifecycle, heartbeat, configuration."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from plansys_bridge.clock import run
from plansys_bridge.errors import ConfigError, HubError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionPerformerStatus,
    ExecutionType,
    PerformerState,
    Topics,
)
from plansys_bridge.performers.base import (
    ActionGoal,
    ActionPerformer,
    PerformerContext,
    arguments_match,
)


class Waiter(ActionPerformer):
    """Runs until told to stop; records the hooks the framework calls."""

    settings_keys = frozenset({"speed"})

    def __init__(self, *a: Any, speed: float = 1.0, **kw: Any) -> None:
        super().__init__(*a, **kw)
        self.speed = speed
        self.calls: list[str] = []

    async def setup(self) -> None:
        self.calls.append("setup")

    async def teardown(self) -> None:
        self.calls.append("teardown")

    async def execute(self, goal: ActionGoal) -> str | None:
        self.calls.append(f"execute {goal.full_name}")
        await asyncio.sleep(1000.0)
        return None

    async def on_cancel(self, goal: ActionGoal) -> None:
        self.calls.append(f"on_cancel {goal.full_name}")


@pytest.mark.parametrize(
    ("spec", "args", "expected"),
    [
        ((), ("r1", "a", "b"), True),
        (("r1",), ("r1", "a", "b"), True),
        (("r2",), ("r1", "a", "b"), False),
        (("", "a", ""), ("r1", "a", "b"), True),
        (("", "x", ""), ("r1", "a", "b"), False),
        (("r1", "a", "b", "extra"), ("r1", "a", "b"), True),  # PlanSys2 only warns on length
        (("", ""), ("r1",), True),
    ],
)
def test_specialized_arguments_match_position_by_position(
    spec: tuple[str, ...], args: tuple[str, ...], expected: bool
) -> None:
    assert arguments_match(spec, args) is expected


def _request(hub: Hub, action: str, args: tuple[str, ...], rid: str) -> None:
    hub.publish(
        Topics.ACTIONS_HUB, ActionExecution(ExecutionType.REQUEST, "", action, args, request_id=rid)
    )


def _to(
    hub: Hub, kind: ExecutionType, node: str, action: str, args: tuple[str, ...], rid: str
) -> None:
    hub.publish(Topics.ACTIONS_HUB, ActionExecution(kind, node, action, args, request_id=rid))


def test_lifecycle_heartbeat_and_cancel(virtual_hub: Hub, hub_recorder: Any) -> None:
    p = Waiter(
        PerformerContext(virtual_hub, virtual_hub.clock),
        "w",
        {"move": ["r1"], "dock": []},
        heartbeat_period=0.5,
    )

    async def main() -> tuple[Any, Any]:
        await virtual_hub.start()
        rec = hub_recorder(virtual_hub, (Topics.ACTIONS_HUB, Topics.PERFORMERS_STATUS))
        await p.start()
        await asyncio.sleep(1.2)
        _request(virtual_hub, "move", ("r2", "a"), "x")  # another robot's: ignored
        _request(virtual_hub, "fly", ("r1",), "x")  # unknown action: ignored
        _request(virtual_hub, "move", ("r1", "a"), "m")
        await asyncio.sleep(0)
        _to(virtual_hub, ExecutionType.CONFIRM, "w", "move", ("r1", "a"), "m")
        await asyncio.sleep(0.6)
        assert p.busy and p.state is PerformerState.RUNNING
        _request(virtual_hub, "dock", (), "d")  # busy: no answer
        _to(virtual_hub, ExecutionType.CANCEL, "someone_else", "move", ("r1", "a"), "m")
        await asyncio.sleep(0)
        assert p.busy
        _to(virtual_hub, ExecutionType.CANCEL, "w", "move", ("r1", "a"), "m")
        await asyncio.sleep(0.1)
        await p.stop()
        await p.stop()  # idempotent
        await asyncio.sleep(0)
        await virtual_hub.close()
        return rec, p.calls

    rec, calls = run(main(), virtual_hub.clock)
    assert calls == ["setup", "execute (move r1 a)", "on_cancel (move r1 a)", "teardown"]
    responses = [m for m in rec.executions() if m.type is ExecutionType.RESPONSE]
    assert [(m.action, m.arguments, m.request_id) for m in responses] == [
        ("move", ("r1", "a"), "m")
    ]
    assert not any(m.type is ExecutionType.FINISH for m in rec.executions())
    statuses = [
        (round(t, 3), m.action, m.state.name)
        for t, m in rec.messages
        if isinstance(m, ActionPerformerStatus)
    ]
    # one status per served action: every 0.5 s, and at each state change
    assert statuses[:6] == [
        (0.0, "move", "READY"),
        (0.0, "dock", "READY"),
        (0.5, "move", "READY"),
        (0.5, "dock", "READY"),
        (1.0, "move", "READY"),
        (1.0, "dock", "READY"),
    ]
    assert (1.2, "move", "RUNNING") in statuses
    assert (1.8, "move", "READY") in statuses
    assert statuses[-2:] == [(1.9, "move", "NOT_READY"), (1.9, "dock", "NOT_READY")]
    first = next(m for _, m in rec.messages if isinstance(m, ActionPerformerStatus))
    assert first.node_name == "w" and first.specialized_arguments == ("r1",)


def test_stop_cancels_the_running_goal_without_finish(virtual_hub: Hub, hub_recorder: Any) -> None:
    p = Waiter(PerformerContext(virtual_hub, virtual_hub.clock), "w", {"move": []})

    async def main() -> Any:
        await virtual_hub.start()
        rec = hub_recorder(virtual_hub)
        await p.start()
        _request(virtual_hub, "move", ("r1",), "m")
        await asyncio.sleep(0)
        _to(virtual_hub, ExecutionType.CONFIRM, "w", "move", ("r1",), "m")
        await asyncio.sleep(5.0)
        await p.stop()
        await asyncio.sleep(0)
        await virtual_hub.close()
        return rec

    rec = run(main(), virtual_hub.clock)
    assert rec.kinds() == [("REQUEST", ""), ("RESPONSE", "w"), ("CONFIRM", "w")]
    assert p.calls[-2:] == ["on_cancel (move r1)", "teardown"]


def test_feedback_outside_a_goal_is_an_error(virtual_hub: Hub) -> None:
    p = Waiter(PerformerContext(virtual_hub, virtual_hub.clock), "w", {"move": []})
    with pytest.raises(HubError, match="no goal running"):
        p.feedback(0.5)


def test_failed_setup_reports_failure_and_raises(virtual_hub: Hub, hub_recorder: Any) -> None:
    class Broken(Waiter):
        async def setup(self) -> None:
            raise OSError("no such device: /dev/ttyACM0")

    p = Broken(PerformerContext(virtual_hub, virtual_hub.clock), "b", {"move": []})

    async def main() -> Any:
        await virtual_hub.start()
        rec = hub_recorder(virtual_hub, (Topics.PERFORMERS_STATUS,))
        with pytest.raises(OSError, match="ttyACM0"):
            await p.start()
        await asyncio.sleep(0)
        return rec

    rec = run(main(), virtual_hub.clock)
    assert [m.state for _, m in rec.messages] == [PerformerState.FAILURE]
    assert not p.running


def test_constructor_rejects_nonsense(virtual_hub: Hub) -> None:
    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    with pytest.raises(ValueError, match="node_name"):
        Waiter(ctx, "", {"move": []})
    with pytest.raises(ValueError, match="serves no action"):
        Waiter(ctx, "w", {})
    with pytest.raises(ValueError, match="heartbeat_period"):
        Waiter(ctx, "w", {"move": []}, heartbeat_period=0)


def test_from_config_builds_with_settings(virtual_hub: Hub) -> None:
    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    [p] = Waiter.from_config(
        {
            "kind": "waiter",
            "name": "w1",
            "actions": {"Move": ["R1", "", None], "dock": None},
            "heartbeat_period": 0.25,
            "speed": 2.0,
        },
        ctx,
        key="performers[3]",
    )
    assert isinstance(p, Waiter)
    assert p.node_name == "w1"
    assert p.actions == {"move": ("r1", "", ""), "dock": ()}
    assert p.heartbeat_period == 0.25 and p.speed == 2.0
    [q] = Waiter.from_config({"name": "w2", "actions": ["move", "dock"]}, ctx)
    assert q.actions == {"move": (), "dock": ()}


@pytest.mark.parametrize(
    ("entry", "key"),
    [
        ({"name": "w", "actions": {"move": []}, "sped": 2}, "performers[1].sped"),
        ({"actions": {"move": []}}, "performers[1].name"),
        ({"name": "w"}, "performers[1].actions"),
        ({"name": "w", "actions": {}}, "performers[1].actions"),
        ({"name": "w", "actions": {"move": "r1"}}, "performers[1].actions.move"),
        ({"name": "w", "actions": {"move": ["r1", 3]}}, "performers[1].actions.move[1]"),
        (
            {"name": "w", "actions": {"move": []}, "heartbeat_period": 0},
            "performers[1].heartbeat_period",
        ),
        (
            {"name": "w", "actions": {"move": []}, "commit_timeout": "soon"},
            "performers[1].commit_timeout",
        ),
        ({"name": "w", "actions": {"move": []}, "speed": "fast", "kind": 3}, "performers[1].kind"),
    ],
)
def test_from_config_errors_name_the_key(virtual_hub: Hub, entry: dict[str, Any], key: str) -> None:
    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    with pytest.raises(ConfigError) as err:
        Waiter.from_config(entry, ctx, key="performers[1]")
    assert err.value.key == key
    assert str(err.value).startswith(key + ": ")
