"""A plain performer hears REQUESTs on a subscription of their own and publishes the
statuses of a change of state together; a subclass that hooks ``_on_action_msg`` and
``_publish`` takes the general paths. Both put the same messages on every topic."""

from __future__ import annotations

import asyncio
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import (
    ActionPerformerStatus,
    ExecutionType,
    PerformerState,
    Topics,
    action_execution,
)
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionGoal, ActionPerformer, PerformerContext

T = ExecutionType
NODES = ["p0", "p1", "p2"]
SPECS = [{"move": ["r1"], "pick": []}, {"move": []}, {"move": ["", "a"], "pick": ["r2"]}]
ARGS = st.sampled_from([("r1", "a"), ("r2", "a"), ("r1", "b"), ("r2",)])
STEP = st.one_of(
    st.tuples(st.just("request"), st.sampled_from(["move", "pick"]), ARGS, st.sampled_from("qr")),
    # about the last REQUEST
    st.tuples(st.sampled_from(["confirm", "confirm", "reject", "cancel"]), st.sampled_from(NODES)),
    st.tuples(st.just("sleep"), st.sampled_from([0.0, 0.5, 1.5])),
    st.tuples(st.just("stop"), st.sampled_from(NODES)),
)


class Plain(ActionPerformer):
    def bid(self, goal: ActionGoal) -> float | None:
        return float(len(self.node_name) + len(goal.arguments))

    async def execute(self, goal: ActionGoal) -> str | None:
        await asyncio.sleep(1.0)
        return None


class Hooked(Plain):
    def _on_action_msg(self, msg: object) -> None:
        super()._on_action_msg(msg)

    def _publish(self, topic: str, msg: object) -> None:
        super()._publish(topic, msg)


async def _messages(cls: type[Plain], steps: list[tuple[Any, ...]]) -> list[tuple[str, object]]:
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)
    await hub.start()
    seen: list[tuple[str, object]] = []
    for topic in (Topics.ACTIONS_HUB, Topics.PERFORMERS_STATUS):
        hub.subscribe(topic, lambda m, t=topic: seen.append((t, m)))
    ctx = PerformerContext(hub, clock)
    performers = {
        n: cls(ctx, n, spec, heartbeat_period=1.0) for n, spec in zip(NODES, SPECS, strict=True)
    }
    for p in performers.values():
        await p.start()
    last = ("move", ("r1", "a"), "q")
    kinds = {"confirm": T.CONFIRM, "reject": T.REJECT, "cancel": T.CANCEL}
    for step in steps:
        kind = step[0]
        if kind == "request":
            last = step[1:]
            msg = action_execution(T.REQUEST, "", last[0], last[1], request_id=last[2])
            hub.publish(Topics.ACTIONS_HUB, msg)
        elif kind in kinds:
            msg = action_execution(kinds[kind], step[1], last[0], last[1], request_id=last[2])
            hub.publish(Topics.ACTIONS_HUB, msg)
        elif kind == "sleep":
            await asyncio.sleep(step[1])
        else:
            await performers[step[1]].stop()
        await asyncio.sleep(0)
    await asyncio.sleep(2.0)  # goals under way end
    for p in performers.values():
        await p.stop()
    await hub.close()
    return seen


@settings(max_examples=120, deadline=None)
@given(steps=st.lists(STEP, max_size=14))
def test_the_request_subscription_and_statuses_together_change_no_message(
    steps: list[tuple[Any, ...]],
) -> None:
    fast = run(_messages(Plain, steps), VirtualClock())
    general = run(_messages(Hooked, steps), VirtualClock())
    assert fast == general


def test_a_plain_performer_takes_the_request_subscription() -> None:
    async def main() -> tuple[int, int]:
        clock = VirtualClock()
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        ctx = PerformerContext(hub, clock)
        plain, hooked = Plain(ctx, "a", {"move": []}), Hooked(ctx, "b", {"move": []})
        await plain.start()
        await hooked.start()
        counts = len(plain._subs), len(hooked._subs)
        await plain.stop()
        await hooked.stop()
        await hub.close()
        return counts

    assert run(main(), VirtualClock()) == (2, 1)


def test_the_statuses_of_a_change_are_one_per_action_in_order() -> None:
    clock = VirtualClock(5.0)

    async def main() -> list[object]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        seen: list[object] = []
        hub.subscribe(Topics.PERFORMERS_STATUS, seen.append)
        p = Plain(
            PerformerContext(hub, clock), "p", {"pick": ["r2"], "move": [], "drop": ["", "a"]}
        )
        await p.start()
        await p.stop()
        await hub.close()
        return seen

    made = [
        ActionPerformerStatus(5.0, state, action, spec, "p")
        for state in (PerformerState.READY, PerformerState.NOT_READY)
        for action, spec in (("pick", ("r2",)), ("move", ()), ("drop", ("", "a")))
    ]
    assert run(main(), clock) == made
