"""A REQUEST reaches only the performers whose specialised arguments match it, and the
indexed routing picks exactly those PlanSys2's rule (checking every performer) picks."""

from __future__ import annotations

import asyncio
from collections import Counter

from hub_counting import Counting
from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics, action_execution
from plansys_bridge.hub.routing import TopicRouter, arguments_match, client_keys, performer_keys
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionGoal, PerformerContext

VALUES = st.sampled_from(["", "r1", "r2", "a", "b"])
SPECS = st.lists(VALUES, max_size=4).map(tuple)
ARGS = st.lists(st.sampled_from(["r1", "r2", "a", "b"]), max_size=4).map(tuple)


def _request(action: str, arguments: tuple[str, ...]) -> ActionExecution:
    return action_execution(ExecutionType.REQUEST, "", action, arguments, request_id="1")


@settings(max_examples=300, deadline=None)
@given(
    performers=st.lists(st.tuples(st.sampled_from(["move", "pick"]), SPECS), max_size=8),
    requests=st.lists(st.tuples(st.sampled_from(["move", "pick", "drop"]), ARGS), max_size=6),
    closed=st.sets(st.integers(0, 7)),
)
def test_indexed_routing_picks_what_the_rule_picks(
    performers: list[tuple[str, tuple[str, ...]]],
    requests: list[tuple[str, tuple[str, ...]]],
    closed: set[int],
) -> None:
    router = TopicRouter(Topics.ACTIONS_HUB)
    got: list[tuple[int, int]] = []
    subs = []
    for i, (action, spec) in enumerate(performers):
        subs.append(
            router.add(
                lambda m, i=i: got.append((len(requests), i)),
                performer_keys(f"n{i}", {action: spec}),
            )
        )
    for i in closed:
        if i < len(subs):
            subs[i].close()
    for action, arguments in requests:
        got.clear()
        msg = _request(action, arguments)
        router.dispatch(msg)
        expected = [
            i
            for i, (served, spec) in enumerate(performers)
            if i not in closed and served == action and arguments_match(spec, arguments)
        ]
        assert [i for _, i in got] == expected  # the same performers, in subscription order
        assert router.wants(msg) == bool(expected)


def test_plain_names_still_hear_every_request_of_their_action() -> None:
    router = TopicRouter(Topics.ACTIONS_HUB)
    heard: list[str] = []
    router.add(lambda m: heard.append("plain"), performer_keys("p", ["move"]))
    router.add(lambda m: heard.append("r1"), performer_keys("q", {"move": ("r1",)}))
    router.add(lambda m: heard.append("any"), performer_keys("s", {"move": ("", "")}))
    router.dispatch(_request("move", ("r2", "a")))
    assert heard == ["plain", "any"]
    heard.clear()
    router.dispatch(_request("move", ("r1", "a")))
    assert heard == ["plain", "r1", "any"]
    heard.clear()
    router.dispatch("not an auction message")  # unroutable: everybody, in order
    assert heard == ["plain", "r1", "any"]


class ServesItself(Counting):
    """Decides what it serves (any robot): must still be asked whatever its spec says."""

    def serves(self, goal: ActionGoal) -> bool:
        return goal.action == "move"


def test_each_robot_hears_only_its_own_requests_and_the_auctions_end_the_same() -> None:
    clock = VirtualClock()

    async def main() -> tuple[list[Counting], ServesItself, list[str]]:
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        ctx = PerformerContext(hub, clock)
        robots = [Counting(ctx, f"r{i}", {"move": [f"r{i}"]}) for i in range(5)]
        itself = ServesItself(ctx, "any", {"move": ["nobody"]})
        for p in (*robots, itself):
            await p.start()
        winners = []
        for i in range(5):
            outcome = await ActionClient(hub, "move", (f"r{i}", "a", "b")).run()
            assert outcome.success
            winners.append(outcome.performer)
            await asyncio.sleep(0)
        for p in (*robots, itself):
            await p.stop()
        await hub.close()
        return robots, itself, winners

    robots, itself, winners = run(main(), clock)
    assert winners == [f"r{i}" for i in range(5)]  # the subscribed-first matching robot
    for robot in robots:
        assert robot.heard == Counter({"REQUEST": 1, "CONFIRM": 1})
    assert itself.heard == Counter({"REQUEST": 5, "REJECT": 5})


class _Tagged(ActionExecution):
    """A subclass: routed by the general route function, not the inlined one."""


@settings(max_examples=200, deadline=None)
@given(
    kind=st.sampled_from(list(ExecutionType)),
    node=st.sampled_from(["", "n0", "n1"]),
    action=st.sampled_from(["move", "pick"]),
    arguments=ARGS,
    rid=st.sampled_from(["", "1", "2"]),
)
def test_the_inlined_route_delivers_as_the_route_function_does(
    kind: ExecutionType, node: str, action: str, arguments: tuple[str, ...], rid: str
) -> None:
    def deliveries(cls: type[ActionExecution]) -> list[int]:
        router = TopicRouter(Topics.ACTIONS_HUB)
        got: list[int] = []
        keysets = [
            performer_keys("n0", {"move": ("r1",)}),
            performer_keys("n1", ["move", "pick"]),
            client_keys("1", "move", ("r1", "a")),
            client_keys("2", "pick", ("r2",)),
            None,
        ]
        for i, keys in enumerate(keysets):
            router.add(lambda m, i=i: got.append(i), keys)
        router.dispatch(cls(kind, node, action, arguments, request_id=rid))
        return got

    assert deliveries(ActionExecution) == deliveries(_Tagged)
