"""The performer's inlined paths decide as the general helpers do: a REJECT releases
the commitment exactly when ``same_goal`` says it names it, a re-sent REQUEST gets
the same RESPONSE again, and ``accepts`` is asked only when a subclass defines it."""

from __future__ import annotations

import asyncio
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics, action_execution
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionGoal, ActionPerformer, PerformerContext
from plansys_bridge.performers.goal import same_goal

T = ExecutionType
RIDS = st.sampled_from(["", "q1", "q2"])
ACTIONS = st.sampled_from(["move", "pick"])
ARGS = st.sampled_from([("r1", "a"), ("r1", "b"), ("r1",)])


class Priced(ActionPerformer):
    def __init__(self, *a: Any, **kw: Any) -> None:
        super().__init__(*a, **kw)
        self.accepted: list[ActionGoal] = []

    def bid(self, goal: ActionGoal) -> float | None:
        return 2.5

    async def execute(self, goal: ActionGoal) -> str | None:
        return None


class Picky(Priced):
    def accepts(self, goal: ActionGoal) -> bool:
        self.accepted.append(goal)
        return goal.arguments[-1] != "b"


async def _performer(cls: type[Priced]) -> tuple[Hub, Priced, list[ActionExecution]]:
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)
    await hub.start()
    sent: list[ActionExecution] = []
    hub.subscribe(Topics.ACTIONS_HUB, lambda m: sent.append(m))  # type: ignore[arg-type]
    p = cls(PerformerContext(hub, clock), "p", {"move": [], "pick": []})
    await p.start()
    return hub, p, sent


@settings(max_examples=200, deadline=None)
@given(
    goal=st.tuples(ACTIONS, ARGS, RIDS),
    reject=st.tuples(ACTIONS, ARGS, RIDS),
    as_list=st.booleans(),
)
def test_a_reject_releases_exactly_when_same_goal_says_it_names_the_commitment(
    goal: tuple[str, tuple[str, ...], str],
    reject: tuple[str, tuple[str, ...], str],
    as_list: bool,
) -> None:
    async def main() -> tuple[bool, bool]:
        hub, p, _sent = await _performer(Priced)
        request = action_execution(T.REQUEST, "", goal[0], goal[1], request_id=goal[2])
        hub.publish(Topics.ACTIONS_HUB, request)
        await asyncio.sleep(0)
        committed = p.committed
        assert committed is not None
        arguments: Any = list(reject[1]) if as_list else reject[1]
        msg = ActionExecution(T.REJECT, "p", reject[0], arguments, request_id=reject[2])
        expected = same_goal(committed, msg)
        p._on_action_msg(msg)
        released = p.committed is None
        await p.stop()
        await hub.close()
        return released, expected

    clock = VirtualClock()
    released, expected = run(main(), clock)
    assert released == expected


def test_a_resent_request_gets_the_same_response_and_accepts_is_asked_when_defined() -> None:
    async def main() -> tuple[list[ActionExecution], Priced, list[ActionExecution], Priced]:
        results: list[Any] = []
        for cls in (Priced, Picky):
            hub, p, sent = await _performer(cls)
            for args in (("r1", "b"), ("r1", "a"), ("r1", "a")):
                request = action_execution(T.REQUEST, "", "move", args, request_id="q")
                hub.publish(Topics.ACTIONS_HUB, request)
                await asyncio.sleep(0)
            await p.stop()
            await hub.close()
            results += [[m for m in sent if m.type is T.RESPONSE], p]
        return results[0], results[1], results[2], results[3]

    plain, plain_p, picky, picky_p = run(main(), VirtualClock())
    # The base class accepts everything: committed to the first REQUEST, it answers
    # only that one again (the others are for another goal).
    assert [(m.arguments, m.bid, m.request_id) for m in plain] == [(("r1", "b"), 2.5, "q")]
    assert plain_p.accepted == []
    # A subclass's accepts() refuses ("r1", "b"), then the re-sent REQUEST is answered
    # with the same RESPONSE as the first.
    assert [(m.arguments, m.bid) for m in picky] == [(("r1", "a"), 2.5), (("r1", "a"), 2.5)]
    assert [g.arguments for g in picky_p.accepted] == [("r1", "b"), ("r1", "a")]
