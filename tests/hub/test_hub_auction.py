"""The auction, both sides, with exact message orders on the virtual clock."""

from __future__ import annotations

import asyncio
import math
from collections.abc import Awaitable, Callable, Mapping, Sequence
from typing import Any

import pytest

from plansys_bridge.clock import run
from plansys_bridge.errors import ConfigError, HubError
from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.performers.base import (
    ActionFailed,
    ActionGoal,
    ActionPerformer,
    PerformerContext,
)
from plansys_bridge.performers.simulated import SimulatedPerformer

REQ, RESP, CONF, REJ, FB, FIN, CAN = (
    "REQUEST",
    "RESPONSE",
    "CONFIRM",
    "REJECT",
    "FEEDBACK",
    "FINISH",
    "CANCEL",
)


def sim(hub: Hub, name: str, actions: Mapping[str, Sequence[str]], **kw: Any) -> SimulatedPerformer:
    return SimulatedPerformer(PerformerContext(hub, hub.clock), name, actions, **kw)


def scenario(hub: Hub, body: Callable[[], Awaitable[Any]], *performers: ActionPerformer) -> Any:
    """Run ``body`` with the performers started, stopping them afterwards."""

    async def main() -> Any:
        await hub.start()
        for p in performers:
            await p.start()
        try:
            return await body()
        finally:
            for p in performers:
                await p.stop()
            await hub.close()

    return run(main(), hub.clock)


def test_normal_run_message_order(virtual_hub: Hub, hub_recorder: Any) -> None:
    p = sim(virtual_hub, "r1_move", {"move": ["r1"]}, durations={"move": 3.0})
    feedback: list[tuple[float, str]] = []

    async def body() -> ActionOutcome:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1", "a", "b"], request_id="plan1:0")
        outcome = await client.run(lambda c, s: feedback.append((c, s)))
        await asyncio.sleep(0)
        body.rec = rec  # type: ignore[attr-defined]
        return outcome

    outcome = scenario(virtual_hub, body, p)
    rec = body.rec  # type: ignore[attr-defined]
    assert rec.timeline() == [
        (0.0, REQ, ""),
        (0.0, RESP, "r1_move"),
        (0.0, CONF, "r1_move"),
        (1.0, FB, "r1_move"),
        (2.0, FB, "r1_move"),
        (3.0, FIN, "r1_move"),
    ]
    assert all(m.request_id == "plan1:0" for m in rec.executions())
    assert all(m.arguments == ("r1", "a", "b") for m in rec.executions())
    assert outcome == ActionOutcome(
        success=True,
        status="(move r1 a b) done in 3 s",
        completion=1.0,
        performer="r1_move",
        reauctioned=0,
    )
    assert [round(c, 3) for c, _ in feedback] == [0.333, 0.667]


def test_cancel_message_order_and_no_finish_after(virtual_hub: Hub, hub_recorder: Any) -> None:
    cancelled: list[ActionGoal] = []

    class Mover(SimulatedPerformer):
        async def on_cancel(self, goal: ActionGoal) -> None:
            cancelled.append(goal)

    p = Mover(
        PerformerContext(virtual_hub, virtual_hub.clock),
        "r1_move",
        {"move": []},
        durations={"move": 10.0},
    )

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1", "a", "b"], request_id="c1")
        task = asyncio.ensure_future(client.run())
        await asyncio.sleep(2.5)
        client.cancel()
        outcome = await task
        await asyncio.sleep(30.0)  # long after: still no FINISH
        return outcome, rec

    outcome, rec = scenario(virtual_hub, body, p)
    assert rec.timeline() == [
        (0.0, REQ, ""),
        (0.0, RESP, "r1_move"),
        (0.0, CONF, "r1_move"),
        (1.0, FB, "r1_move"),
        (2.0, FB, "r1_move"),
        (2.5, CAN, "r1_move"),
    ]
    assert outcome.cancelled and not outcome.success and outcome.performer == "r1_move"
    assert cancelled == [ActionGoal("move", ("r1", "a", "b"), "c1")]
    assert p.goal is None and not p.busy


def test_cancelling_the_awaiting_task_cancels_the_performer(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    p = sim(virtual_hub, "p", {"cook": []}, durations={"cook": 21.0}, feedback_period=None)

    async def body() -> Any:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "cook", ["r1", "soup"], request_id="k")
        task = asyncio.ensure_future(client.run())
        await asyncio.sleep(4.0)
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        await asyncio.sleep(30.0)
        return rec

    rec = scenario(virtual_hub, body, p)
    assert rec.kinds() == [(REQ, ""), (RESP, "p"), (CONF, "p"), (CAN, "p")]


def test_no_request_after_giving_up(virtual_hub: Hub, hub_recorder: Any) -> None:
    policy = AuctionPolicy(retry_period=1.0, give_up_after=5.0)
    late = sim(virtual_hub, "late", {"move": []})

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r9", "a", "b"], request_id="g", policy=policy)
        outcome = await client.run()
        await late.start()  # a performer that shows up after the give-up gets nothing
        await asyncio.sleep(600.0)
        await late.stop()
        return outcome, rec

    outcome, rec = scenario(virtual_hub, body)
    assert rec.timeline() == [(float(t), REQ, "") for t in range(5)]
    assert not outcome.success and outcome.gave_up
    assert outcome.status == "no performer answered the REQUEST for (move r9 a b) within 5 s"
    assert late.executed == 0


def test_plansys2_default_retries_every_second_for_thirty_seconds(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    async def body() -> Any:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1"], request_id="d")
        await client.run()
        await asyncio.sleep(120.0)
        return rec, client

    rec, client = scenario(virtual_hub, body)
    assert [t for t, _, _ in rec.timeline()] == [float(t) for t in range(30)]
    assert client.requests_sent == 30


def test_dead_performer_is_cancelled_and_the_action_re_auctioned(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    p1 = sim(virtual_hub, "p1", {"move": []}, durations={"move": 4.2})
    p2 = sim(virtual_hub, "p2", {"move": []}, durations={"move": 3.0})
    p1.die_during_next()  # goes silent at 2.1 s (half the action)
    policy = AuctionPolicy(liveness_timeout=3.0)

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1", "a", "b"], request_id="x", policy=policy)
        outcome = await client.run()
        await asyncio.sleep(0)
        return outcome, rec

    outcome, rec = scenario(virtual_hub, body, p1, p2)
    assert rec.timeline() == [
        (0.0, REQ, ""),
        (0.0, RESP, "p1"),
        (0.0, RESP, "p2"),
        (0.0, CONF, "p1"),
        (0.0, REJ, "p2"),
        (1.0, FB, "p1"),
        (2.0, FB, "p1"),
        # p1 goes silent at 2.1; its last sign of life (feedback, RUNNING heartbeat)
        # was at 2.0, so it is declared lost at 5.0
        (5.0, CAN, "p1"),
        (5.0, REQ, ""),
        (5.0, RESP, "p2"),
        (5.0, CONF, "p2"),
        (6.0, FB, "p2"),
        (7.0, FB, "p2"),
        (8.0, FIN, "p2"),
    ]
    assert outcome.success
    assert outcome.performer == "p2"
    assert outcome.reauctioned == 1
    assert outcome.lost_performers == ("p1",)


def test_a_lost_performer_is_re_auctioned_once_then_the_action_fails(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    p1 = sim(virtual_hub, "p1", {"move": []}, durations={"move": 4.0})
    p2 = sim(virtual_hub, "p2", {"move": []}, durations={"move": 4.0})
    p1.die_during_next()
    p2.die_during_next()
    policy = AuctionPolicy(liveness_timeout=3.0, reauctions=1)

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1"], request_id="x", policy=policy)
        return await client.run(), rec

    outcome, rec = scenario(virtual_hub, body, p1, p2)
    assert not outcome.success
    assert outcome.lost_performers == ("p1", "p2")
    assert outcome.reauctioned == 1
    assert outcome.status == (
        "performer p2 lost: neither feedback nor heartbeat for 3 s; "
        "re-auctioned 1 time(s), giving up"
    )
    assert rec.kinds().count((REQ, "")) == 2
    assert rec.kinds()[-1] == (CAN, "p2")


def test_a_lost_finish_ends_in_a_re_auction(virtual_hub: Hub, hub_recorder: Any) -> None:
    p1 = sim(virtual_hub, "p1", {"move": []}, durations={"move": 2.5})
    p2 = sim(virtual_hub, "p2", {"move": []}, durations={"move": 1.5})
    p1.lose_next_finish()
    policy = AuctionPolicy(liveness_timeout=3.0)

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1"], request_id="y", policy=policy)
        return await client.run(), rec

    outcome, rec = scenario(virtual_hub, body, p1, p2)
    assert outcome.success and outcome.performer == "p2" and outcome.lost_performers == ("p1",)
    # p1 finished at 2.5 without FINISH and heartbeats READY since: its last sign of
    # life for this action was at 2.0, so it is lost at 5.0; idle again, it answers
    # the new auction but is excluded.
    assert rec.timeline()[5:] == [
        (1.0, FB, "p1"),
        (2.0, FB, "p1"),
        (5.0, CAN, "p1"),
        (5.0, REQ, ""),
        (5.0, RESP, "p1"),
        (5.0, RESP, "p2"),
        (5.0, REJ, "p1"),
        (5.0, CONF, "p2"),
        (6.0, FB, "p2"),
        (6.5, FIN, "p2"),
    ]
    assert p1.stats["lost_finish"] == 1


def test_running_heartbeats_keep_a_quiet_performer_alive(virtual_hub: Hub) -> None:
    p = sim(virtual_hub, "p", {"cook": []}, durations={"cook": 21.0}, feedback_period=None)
    policy = AuctionPolicy(liveness_timeout=2.0)

    async def body() -> ActionOutcome:
        return await ActionClient(virtual_hub, "cook", ["r1"], request_id="z", policy=policy).run()

    outcome = scenario(virtual_hub, body, p)
    assert outcome.success and outcome.reauctioned == 0 and outcome.lost_performers == ()


def test_specialised_performers_serve_only_their_robot(virtual_hub: Hub, hub_recorder: Any) -> None:
    robots = ["r1", "r2", "r3"]
    performers = [
        sim(virtual_hub, f"{r}_move", {"move": [r, "", ""]}, durations={"move": 5.0})
        for r in robots
    ]

    async def body() -> tuple[list[ActionOutcome], Any]:
        rec = hub_recorder(virtual_hub)
        clients = [
            ActionClient(virtual_hub, "move", [r, "a", "b"], request_id=f"m{i}")
            for i, r in enumerate(reversed(robots))
        ]
        outcomes = await asyncio.gather(*(c.run() for c in clients))
        return list(outcomes), rec

    outcomes, rec = scenario(virtual_hub, body, *performers)
    assert [o.performer for o in outcomes] == ["r3_move", "r2_move", "r1_move"]
    assert all(o.success for o in outcomes)
    # all three ran in parallel: every FINISH at 5.0
    assert [t for t, k, _ in rec.timeline() if k == FIN] == [5.0, 5.0, 5.0]
    for m in rec.executions():
        if m.type is ExecutionType.RESPONSE:
            assert m.node_id == f"{m.arguments[0]}_move"


def test_best_bid_confirms_the_cheapest_and_rejects_the_others(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    class Bidder(SimulatedPerformer):
        def __init__(self, *a: Any, cost: float | None, **kw: Any) -> None:
            super().__init__(*a, **kw)
            self.cost = cost

        def bid(self, goal: ActionGoal) -> float | None:
            return self.cost

    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    costs = {"far": 9.0, "near": 2.0, "near_too": 2.0, "nobid": None, "refuses": math.inf}
    bidders = [
        Bidder(ctx, n, {"move": []}, cost=c, durations={"move": 1.0}) for n, c in costs.items()
    ]
    policy = AuctionPolicy(selection="best_bid", bid_window=0.2)

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1"], request_id="b", policy=policy)
        return await client.run(), rec

    outcome, rec = scenario(virtual_hub, body, *bidders)
    assert outcome.performer == "near"
    assert rec.timeline() == [
        (0.0, REQ, ""),
        (0.0, RESP, "far"),
        (0.0, RESP, "near"),
        (0.0, RESP, "near_too"),
        (0.0, RESP, "nobid"),
        (0.2, CONF, "near"),
        (0.2, REJ, "far"),
        (0.2, REJ, "near_too"),
        (0.2, REJ, "nobid"),
        (1.2, FIN, "near"),
    ]
    bids = {m.node_id: m.bid for m in rec.executions() if m.type is ExecutionType.RESPONSE}
    assert bids == {"far": 9.0, "near": 2.0, "near_too": 2.0, "nobid": None}


def test_first_responder_wins_and_late_responders_are_rejected(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    a = sim(virtual_hub, "a", {"move": []}, durations={"move": 1.0})
    b = sim(virtual_hub, "b", {"move": []}, durations={"move": 1.0})

    async def body() -> Any:
        rec = hub_recorder(virtual_hub)
        await ActionClient(virtual_hub, "move", ["r1"], request_id="f").run()
        return rec

    rec = scenario(virtual_hub, body, a, b)
    assert rec.kinds() == [(REQ, ""), (RESP, "a"), (RESP, "b"), (CONF, "a"), (REJ, "b"), (FIN, "a")]
    assert b.committed is None and b.executed == 0


def test_a_committed_performer_does_not_bid_elsewhere_and_a_busy_one_neither(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    p = sim(virtual_hub, "p", {"move": []}, durations={"move": 2.0}, feedback_period=None)
    slow = AuctionPolicy(selection="best_bid", bid_window=0.5)

    async def body() -> tuple[list[ActionOutcome], Any]:
        rec = hub_recorder(virtual_hub)
        first = ActionClient(virtual_hub, "move", ["r1"], request_id="A", policy=slow)
        second = ActionClient(virtual_hub, "move", ["r2"], request_id="B")
        t1 = asyncio.ensure_future(first.run())
        await asyncio.sleep(0.1)  # p is committed to A (waiting for its bid window)
        outcomes = await asyncio.gather(t1, second.run())
        return list(outcomes), rec

    outcomes, rec = scenario(virtual_hub, body, p)
    assert [o.success for o in outcomes] == [True, True]
    assert rec.timeline(request_ids=True) == [
        (0.0, REQ, "", "A"),
        (0.0, RESP, "p", "A"),
        (0.1, REQ, "", "B"),  # committed to A (its bid window is open): no answer
        (0.5, CONF, "p", "A"),
        (1.1, REQ, "", "B"),  # busy with A: no answer
        (2.1, REQ, "", "B"),
        (2.5, FIN, "p", "A"),
        # p announces READY after A: B asks again at once, not at its next retry (3.1)
        (2.5, REQ, "", "B"),
        (2.5, RESP, "p", "B"),
        (2.5, CONF, "p", "B"),
        (4.5, FIN, "p", "B"),
    ]


def test_commitment_expires_when_no_confirm_comes(virtual_hub: Hub, hub_recorder: Any) -> None:
    p = sim(virtual_hub, "p", {"move": []}, commit_timeout=2.0)

    def request(rid: str) -> None:
        virtual_hub.publish(
            Topics.ACTIONS_HUB,
            ActionExecution(ExecutionType.REQUEST, "", "move", ("r1",), request_id=rid),
        )

    async def body() -> Any:
        rec = hub_recorder(virtual_hub)
        request("never-confirmed")
        await asyncio.sleep(1.0)
        request("other")  # still committed: ignored
        await asyncio.sleep(1.5)
        request("other")  # commitment expired at 2.0: answered
        await asyncio.sleep(0.1)
        return rec

    rec = scenario(virtual_hub, body, p)
    assert rec.timeline(request_ids=True) == [
        (0.0, REQ, "", "never-confirmed"),
        (0.0, RESP, "p", "never-confirmed"),
        (1.0, REQ, "", "other"),
        (2.5, REQ, "", "other"),
        (2.5, RESP, "p", "other"),
    ]


def test_identical_actions_of_two_plans_are_kept_apart_by_request_id(
    virtual_hub: Hub,
) -> None:
    fast = sim(virtual_hub, "fast", {"move": []}, durations={"move": 1.0})
    slow = sim(virtual_hub, "slow", {"move": []}, durations={"move": 7.0})

    async def body() -> list[tuple[ActionOutcome, float]]:
        loop = asyncio.get_running_loop()

        async def one(rid: str, delay: float) -> tuple[ActionOutcome, float]:
            await asyncio.sleep(delay)
            outcome = await ActionClient(virtual_hub, "move", ["r1", "a"], request_id=rid).run()
            return outcome, loop.time()

        return list(await asyncio.gather(one("plan1:3", 0.0), one("plan2:3", 0.5)))

    (o1, t1), (o2, t2) = scenario(virtual_hub, body, fast, slow)
    # fast's FINISH at 1.0 has the same action text but must not end plan2's action
    assert (o1.performer, t1) == ("fast", 1.0)
    assert (o2.performer, t2) == ("slow", 7.5)


class Flaky(ActionPerformer):
    """Fails in the three ways a performer can, then works."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        super().__init__(*a, **kw)
        self.calls = 0

    async def execute(self, goal: ActionGoal) -> str | None:
        self.calls += 1
        await self.clock.sleep(1.0)
        if goal.arguments[0] == "bug":
            return str(1 / 0)
        if goal.arguments[0] == "refused":
            raise ActionFailed("gripper jammed")
        self.feedback(0.5, "half way")
        return None


def test_execute_failures_finish_unsuccessfully_and_the_performer_survives(
    virtual_hub: Hub,
) -> None:
    p = Flaky(PerformerContext(virtual_hub, virtual_hub.clock), "flaky", {"grab": []})

    async def body() -> list[ActionOutcome]:
        return [
            await ActionClient(virtual_hub, "grab", [arg], request_id=arg).run()
            for arg in ("bug", "refused", "ok")
        ]

    bug, refused, ok = scenario(virtual_hub, body, p)
    assert not bug.success and bug.status == "ZeroDivisionError: division by zero"
    assert not refused.success and refused.status == "gripper jammed"
    assert ok.success and ok.status == "succeeded" and ok.completion == 1.0
    assert p.calls == 3


def test_a_performer_that_never_answers_leaves_the_action_to_others(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    mute = sim(virtual_hub, "mute", {"move": []}, faults={"never_answer": True})
    ok = sim(virtual_hub, "ok", {"move": []})

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        return await ActionClient(virtual_hub, "move", ["r1"], request_id="n").run(), rec

    outcome, rec = scenario(virtual_hub, body, mute, ok)
    assert outcome.performer == "ok"
    assert ("RESPONSE", "mute") not in rec.kinds()


def test_cancel_during_the_auction_rejects_the_bidders(virtual_hub: Hub, hub_recorder: Any) -> None:
    p = sim(virtual_hub, "p", {"move": []})
    policy = AuctionPolicy(selection="best_bid", bid_window=1.0)

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1"], request_id="q", policy=policy)
        task = asyncio.ensure_future(client.run())
        await asyncio.sleep(0.5)
        client.cancel()
        outcome = await task
        await asyncio.sleep(0)
        return outcome, rec

    outcome, rec = scenario(virtual_hub, body, p)
    assert outcome.cancelled and outcome.performer == ""
    assert rec.kinds() == [(REQ, ""), (RESP, "p"), (REJ, "p")]
    assert p.committed is None


def test_run_twice_is_an_error(virtual_hub: Hub) -> None:
    p = sim(virtual_hub, "p", {"move": []}, default_duration=0.0)

    async def body() -> None:
        client = ActionClient(virtual_hub, "move", [], request_id="t")
        await client.run()
        with pytest.raises(HubError, match="only once"):
            await client.run()

    scenario(virtual_hub, body, p)


def test_auction_policy_from_config_names_the_key() -> None:
    policy = AuctionPolicy.from_config({"selection": "best_bid", "bid_window": 0.1})
    assert policy.selection == "best_bid" and policy.bid_window == 0.1
    assert AuctionPolicy.from_config(None) == AuctionPolicy()
    with pytest.raises(ConfigError) as err:
        AuctionPolicy.from_config({"retry_perid": 1.0})
    assert err.value.key == "auction.retry_perid"
    with pytest.raises(ConfigError) as err:
        AuctionPolicy.from_config({"give_up_after": -1})
    assert err.value.key == "auction.give_up_after"
    with pytest.raises(ConfigError) as err:
        AuctionPolicy.from_config({"selection": "cheapest"}, key="mission.auction")
    assert err.value.key == "mission.auction.selection"
    with pytest.raises(ConfigError) as err:
        AuctionPolicy.from_config({"reauctions": True})
    assert err.value.key == "auction.reauctions"


def test_confirm_callback_names_each_confirmed_performer(virtual_hub: Hub) -> None:
    p1 = sim(virtual_hub, "p1", {"move": []}, durations={"move": 4.2})
    p2 = sim(virtual_hub, "p2", {"move": []}, durations={"move": 4.0})
    p1.die_during_next()
    confirmed: list[tuple[float, str]] = []

    async def body() -> ActionOutcome:
        loop = asyncio.get_running_loop()
        client = ActionClient(
            virtual_hub, "move", ["r1"], request_id="cb", policy=AuctionPolicy(liveness_timeout=3)
        )
        return await client.run(confirm_cb=lambda node: confirmed.append((loop.time(), node)))

    outcome = scenario(virtual_hub, body, p1, p2)
    assert outcome.success
    assert confirmed == [(0.0, "p1"), (5.0, "p2")]


def test_cancel_before_run_sends_nothing(virtual_hub: Hub, hub_recorder: Any) -> None:
    p = sim(virtual_hub, "p", {"move": []})

    async def body() -> tuple[ActionOutcome, Any]:
        rec = hub_recorder(virtual_hub)
        client = ActionClient(virtual_hub, "move", ["r1"], request_id="early")
        client.cancel()
        outcome = await client.run()
        client.cancel()  # after the end: nothing happens
        await asyncio.sleep(1.0)
        return outcome, rec

    outcome, rec = scenario(virtual_hub, body, p)
    assert outcome.cancelled and rec.kinds() == []


def test_a_plansys2_performer_without_request_ids_is_matched_by_action_text(
    virtual_hub: Hub, hub_recorder: Any
) -> None:
    """PlanSys2's performers know nothing of request_id; the action text identifies."""

    def legacy(msg: object) -> None:
        if not isinstance(msg, ActionExecution):
            return
        reply = None
        if msg.type is ExecutionType.REQUEST:
            reply = ExecutionType.RESPONSE
        elif msg.type is ExecutionType.CONFIRM and msg.node_id == "legacy":
            reply = ExecutionType.FINISH
        if reply is not None:
            virtual_hub.publish(
                Topics.ACTIONS_HUB,
                ActionExecution(reply, "legacy", msg.action, msg.arguments, success=True),
            )

    async def body() -> ActionOutcome:
        virtual_hub.subscribe(Topics.ACTIONS_HUB, legacy)
        return await ActionClient(virtual_hub, "move", ["r1", "a"], request_id="new").run()

    outcome = scenario(virtual_hub, body)
    assert outcome.success and outcome.performer == "legacy" and outcome.status == "succeeded"
