"""A performer's answer to a REQUEST: decided off the message, one goal per REQUEST."""

from __future__ import annotations

import asyncio
from typing import Any

from plansys_bridge.clock import run
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.performers.base import ActionGoal, ActionPerformer, PerformerContext
from plansys_bridge.performers.goal import goal_of


class Bidder(ActionPerformer):
    """Records every goal it is asked to bid on."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        super().__init__(*a, **kw)
        self.asked: list[ActionGoal] = []

    def bid(self, goal: ActionGoal) -> float | None:
        self.asked.append(goal)
        return 1.0

    async def execute(self, goal: ActionGoal) -> str | None:
        return None


class OnlyKitchen(Bidder):
    """Decides what it serves itself: only moves to the kitchen."""

    def serves(self, goal: ActionGoal) -> bool:
        return goal.arguments[-1:] == ("kitchen",)


def _request(hub: Hub, args: tuple[str, ...], rid: str) -> None:
    msg = ActionExecution(ExecutionType.REQUEST, "", "move", args, request_id=rid)
    hub.publish(Topics.ACTIONS_HUB, msg)


def test_performers_handed_one_request_share_its_goal(virtual_hub: Hub, hub_recorder: Any) -> None:
    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    a = Bidder(ctx, "a", {"move": []})
    b = Bidder(ctx, "b", {"move": ["r1"]})
    other = Bidder(ctx, "other", {"move": ["r2"]})  # another robot's: never asked

    async def main() -> Any:
        await virtual_hub.start()
        rec = hub_recorder(virtual_hub, (Topics.ACTIONS_HUB,))
        for p in (a, b, other):
            await p.start()
        _request(virtual_hub, ("r1", "x", "y"), "q1")
        await asyncio.sleep(0)
        _request(virtual_hub, ("r1", "x", "y"), "q1")  # re-sent: same answer again
        await asyncio.sleep(0)
        for p in (a, b, other):
            await p.stop()
        await virtual_hub.close()
        return rec

    rec = run(main(), virtual_hub.clock)
    assert a.asked == b.asked == [ActionGoal("move", ("r1", "x", "y"), "q1")]
    assert a.asked[0] is b.asked[0]
    assert other.asked == []
    responses = [m.node_id for m in rec.executions() if m.type is ExecutionType.RESPONSE]
    assert sorted(responses) == ["a", "a", "b", "b"]


def test_a_subclass_deciding_what_it_serves_is_still_asked(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    p = OnlyKitchen(PerformerContext(virtual_hub, virtual_hub.clock), "k", {"move": []})

    async def main() -> Any:
        await virtual_hub.start()
        rec = hub_recorder(virtual_hub, (Topics.ACTIONS_HUB,))
        await p.start()
        _request(virtual_hub, ("r1", "x", "garage"), "q1")
        _request(virtual_hub, ("r1", "x", "kitchen"), "q2")
        await asyncio.sleep(0)
        await p.stop()
        await virtual_hub.close()
        return rec

    rec = run(main(), virtual_hub.clock)
    responses = [m.request_id for m in rec.executions() if m.type is ExecutionType.RESPONSE]
    assert responses == ["q2"]


def test_goal_of_gives_a_new_goal_for_a_new_request() -> None:
    first = ActionExecution(ExecutionType.REQUEST, "", "move", ("r1",), request_id="q1")
    second = ActionExecution(ExecutionType.REQUEST, "", "move", ("r1",), request_id="q2")
    assert goal_of(first) is goal_of(first)
    assert goal_of(second) == ActionGoal("move", ("r1",), "q2")
    assert goal_of(first) == ActionGoal("move", ("r1",), "q1")
