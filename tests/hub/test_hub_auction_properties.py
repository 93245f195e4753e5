"""Protocol invariants under random performers, faults and cancels (hypothesis)."""

from __future__ import annotations

import asyncio
from collections import defaultdict
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import FaultPlan, SimulatedPerformer

T = ExecutionType
CLIENT_SENT = (T.REQUEST, T.CONFIRM, T.REJECT, T.CANCEL)


class CountingPerformer(SimulatedPerformer):
    """Records how many goals ran at once (must never exceed one)."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        super().__init__(*a, **kw)
        self.now_running = 0
        self.max_running = 0
        self.cancels_heard: set[str] = set()
        self.spoke_after_cancel: list[str] = []

    def _on_cancel_msg(self, msg: ActionExecution) -> None:
        self.cancels_heard.add(msg.request_id)
        super()._on_cancel_msg(msg)

    def _send(self, kind: ExecutionType, goal: Any, **kw: Any) -> None:
        if kind in (T.FEEDBACK, T.FINISH) and goal.request_id in self.cancels_heard:
            self.spoke_after_cancel.append(f"{kind.name} {goal.request_id}")
        super()._send(kind, goal, **kw)

    async def execute(self, goal: Any) -> str | None:
        self.now_running += 1
        self.max_running = max(self.max_running, self.now_running)
        try:
            return await super().execute(goal)
        finally:
            self.now_running -= 1


performer_st = st.fixed_dictionaries(
    {
        "robot": st.sampled_from(["r1", "r2", ""]),
        "duration": st.sampled_from([0.0, 0.5, 2.0, 7.0]),
        "success_rate": st.sampled_from([1.0, 0.7]),
        "feedback_period": st.sampled_from([None, 1.0]),
        "faults": st.builds(
            FaultPlan,
            die_rate=st.sampled_from([0.0, 0.3]),
            lose_finish_rate=st.sampled_from([0.0, 0.3]),
            never_answer=st.booleans(),
            revive_after=st.sampled_from([None, 4.0]),
        ),
    }
)
action_st = st.tuples(
    st.sampled_from(["r1", "r2", "r3"]),  # r3: nobody serves it
    st.floats(0.0, 5.0),  # start delay
    st.one_of(st.none(), st.floats(0.0, 12.0)),  # cancel after
)
policy_st = st.builds(
    AuctionPolicy,
    retry_period=st.sampled_from([0.5, 1.0]),
    give_up_after=st.sampled_from([3.0, 10.0]),
    selection=st.sampled_from(["first", "best_bid"]),
    bid_window=st.sampled_from([0.0, 0.3]),
    liveness_timeout=st.sampled_from([2.5, 5.0]),
    reauctions=st.sampled_from([0, 1, 2]),
)


def make_performers(
    hub: Hub, performers: list[dict[str, Any]], seed: int
) -> list[CountingPerformer]:
    """The performers a scenario's ``performers`` describes, on ``hub`` (not started)."""
    ctx = PerformerContext(hub, hub.clock)
    return [
        CountingPerformer(
            ctx,
            f"p{i}",
            {"move": [spec["robot"]]},
            default_duration=spec["duration"],
            success_rate=spec["success_rate"],
            feedback_period=spec["feedback_period"],
            faults=spec["faults"],
            seed=seed,
        )
        for i, spec in enumerate(performers)
    ]


def _simulate(
    performers: list[dict[str, Any]],
    actions: list[tuple[str, float, float | None]],
    policy: AuctionPolicy,
    seed: int,
) -> tuple[
    list[tuple[float, ActionExecution]], list[tuple[ActionOutcome, float]], list[CountingPerformer]
]:
    hub = Hub(InProcessTransport(), VirtualClock())
    perfs = make_performers(hub, performers, seed)
    log: list[tuple[float, ActionExecution]] = []

    async def one(
        i: int, robot: str, delay: float, cancel_after: float | None
    ) -> tuple[ActionOutcome, float]:
        loop = asyncio.get_running_loop()
        await asyncio.sleep(delay)
        client = ActionClient(hub, "move", [robot, "a", "b"], request_id=f"a{i}", policy=policy)
        if cancel_after is not None:
            loop.call_later(cancel_after, client.cancel)
        outcome = await client.run()
        return outcome, loop.time()

    async def main() -> list[tuple[ActionOutcome, float]]:
        await hub.start()
        loop = asyncio.get_running_loop()
        hub.subscribe(
            Topics.ACTIONS_HUB,
            lambda m: log.append((loop.time(), m)) if isinstance(m, ActionExecution) else None,
        )
        for p in perfs:
            await p.start()
        outcomes = await asyncio.wait_for(
            asyncio.gather(*(one(i, *a) for i, a in enumerate(actions))), timeout=10_000
        )
        await asyncio.sleep(policy.give_up_after + 20.0)  # anything still coming would show
        for p in perfs:
            await p.stop()
        await hub.close()
        return list(outcomes)

    outcomes = run(main(), hub.clock)
    return log, outcomes, perfs


SCENARIOS = {
    "performers": st.lists(performer_st, min_size=0, max_size=4),
    "actions": st.lists(action_st, min_size=1, max_size=5),
    "policy": policy_st,
    "seed": st.integers(0, 1000),
}
"""What :func:`_simulate` takes, as ``@given`` keyword arguments."""


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(**SCENARIOS)
def test_protocol_invariants(
    performers: list[dict[str, Any]],
    actions: list[tuple[str, float, float | None]],
    policy: AuctionPolicy,
    seed: int,
) -> None:
    log, outcomes, perfs = _simulate(performers, actions, policy, seed)
    assert len(outcomes) == len(actions)  # every action ended: nothing hangs
    by_request: dict[str, list[tuple[float, ActionExecution]]] = defaultdict(list)
    for t, m in log:
        by_request[m.request_id].append((t, m))
    for i, (outcome, ended_at) in enumerate(outcomes):
        msgs = by_request[f"a{i}"]
        # the client says nothing more once run() returned (no REQUEST after giving up)
        assert all(t <= ended_at for t, m in msgs if m.type in CLIENT_SENT)
        requests = [t for t, m in msgs if m.type is T.REQUEST]
        responders = set()
        confirmed: list[str] = []
        cancelled: set[str] = set()
        for _, m in msgs:
            if m.type is T.RESPONSE:
                responders.add(m.node_id)
            elif m.type is T.CONFIRM:
                assert m.node_id in responders, "CONFIRM to a node that never answered"
                confirmed.append(m.node_id)
            elif m.type is T.CANCEL:
                assert m.node_id in confirmed, "CANCEL to a node never confirmed"
                cancelled.add(m.node_id)
            elif m.type in (T.FEEDBACK, T.FINISH):
                assert m.node_id in confirmed, f"{m.type.name} from a node never confirmed"
                # FEEDBACK or FINISH may cross a CANCEL in flight (both sent at one
                # instant); what must never happen is either one sent once the
                # CANCEL was heard, which the performers check themselves below.
        # a node is confirmed at most once per action, and at most 1 + reauctions nodes
        assert len(confirmed) == len(set(confirmed)) <= 1 + policy.reauctions
        # REQUESTs: one per retry_period slot (a performer becoming free may take its
        # slot early), for give_up_after at most, per auction
        per_auction = round(policy.give_up_after / policy.retry_period)
        assert len(requests) <= (1 + policy.reauctions) * per_auction
        if outcome.gave_up and not confirmed:
            assert len(requests) == per_auction
            assert requests[-1] - requests[0] <= (per_auction - 1) * policy.retry_period + 1e-9
        if outcome.success:
            finishes = [m for _, m in msgs if m.type is T.FINISH]
            assert finishes[-1].success and finishes[-1].node_id == outcome.performer
        if outcome.cancelled and outcome.performer:
            assert (T.CANCEL, outcome.performer) in [(m.type, m.node_id) for _, m in msgs]
        assert outcome.reauctioned <= policy.reauctions
        assert set(outcome.lost_performers) <= cancelled
    for p in perfs:
        assert p.max_running <= 1  # a performer never runs two goals at once
        assert p.spoke_after_cancel == []  # no FEEDBACK/FINISH once a CANCEL was heard
        if not p.dead:
            assert not p.busy and p.committed is None  # ended idle, uncommitted
