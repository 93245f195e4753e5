"""A plain performer takes the short ways (REQUESTs handed over by the router without
checking their arguments again, the base class's bid not asked, the CONFIRM checked
and the FINISH sent inline, statuses stamped off the virtual loop); a subclass that
hooks ``_on_action_msg``, ``_send`` and ``bid`` takes the general ones. Both must
send the same messages, in the same order, on every topic."""

from __future__ import annotations

import asyncio
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, VirtualTimeEventLoop, run, stamp_loop
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ExecutionType, Topics, action_execution, performer_statuses
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionGoal, ActionPerformer, PerformerContext

T = ExecutionType
NAMES = st.sampled_from(["", "r1", "r2"])


class Plain(ActionPerformer):
    async def execute(self, goal: ActionGoal) -> str | None:
        await asyncio.sleep(0)
        return "done" if goal.arguments[-1:] == ("a",) else None


class General(Plain):
    """Every general path: hooked dispatch, hooked send, a bid of its own (None)."""

    def _on_action_msg(self, msg: object) -> None:
        super()._on_action_msg(msg)

    def _send(self, kind: ExecutionType, goal: Any, **kw: Any) -> None:
        super()._send(kind, goal, **kw)

    def bid(self, goal: ActionGoal) -> float | None:
        return None


async def _exchange(cls: type[Plain], case: dict[str, Any]) -> list[tuple[str, object]]:
    clock = VirtualClock(start=5.0)
    hub = Hub(InProcessTransport(), clock)
    await hub.start()
    seen: list[tuple[str, object]] = []
    for topic in (Topics.ACTIONS_HUB, Topics.PERFORMERS_STATUS):
        hub.subscribe(topic, lambda m, t=topic: seen.append((t, m)))  # type: ignore[misc]
    p = cls(PerformerContext(hub, clock), "p", case["actions"], commit_timeout=2.0)
    await p.start()
    request = action_execution(
        T.REQUEST, "", case["action"], case["arguments"], request_id=case["rid"]
    )
    hub.publish(Topics.ACTIONS_HUB, request)
    await asyncio.sleep(case["wait"])
    confirm = action_execution(
        T.CONFIRM, "p", case["action"], case["confirmed"], request_id=case["confirm_rid"]
    )
    hub.publish(Topics.ACTIONS_HUB, confirm)
    for _ in range(4):
        await asyncio.sleep(0)
    await p.stop()
    await hub.close()
    return seen


CASES = st.fixed_dictionaries(
    {
        "actions": st.dictionaries(
            st.sampled_from(["move", "pick"]), st.lists(NAMES, max_size=2), min_size=1
        ),
        "action": st.sampled_from(["move", "pick", "drop"]),
        "arguments": st.lists(NAMES.filter(bool), min_size=1, max_size=2).map(tuple),
        "rid": st.sampled_from(["", "q1"]),
        "wait": st.sampled_from([0.0, 1.0, 3.0]),
        "confirmed": st.sampled_from([("r1",), ("r1", "a"), ("r2", "r1")]),
        "confirm_rid": st.sampled_from(["", "q1", "q2"]),
    }
)


@settings(max_examples=150, deadline=None)
@given(case=CASES)
def test_the_short_ways_send_what_the_general_ones_send(case: dict[str, Any]) -> None:
    case["confirmed"] = case["arguments"] if case["confirm_rid"] == "q1" else case["confirmed"]
    plain = run(_exchange(Plain, case), VirtualClock())
    general = run(_exchange(General, case), VirtualClock())
    assert plain == general


def test_a_hooked_send_hears_the_finish() -> None:
    """Fault injection hooks ``_send``/``_finish``: the FINISH still goes through them."""
    sent: list[str] = []

    class Hooked(Plain):
        def _send(self, kind: ExecutionType, goal: Any, **kw: Any) -> None:
            sent.append(kind.name)
            super()._send(kind, goal, **kw)

    case = {
        "actions": {"move": ["r1"]},
        "action": "move",
        "arguments": ("r1", "a"),
        "rid": "q1",
        "wait": 0.0,
        "confirmed": ("r1", "a"),
        "confirm_rid": "q1",
    }
    seen = run(_exchange(Hooked, case), VirtualClock())
    assert sent == ["FINISH"]
    kinds = [m.type for t, m in seen if t == Topics.ACTIONS_HUB]  # type: ignore[attr-defined]
    assert kinds == [T.REQUEST, T.RESPONSE, T.CONFIRM, T.FINISH]


def test_stamp_loop_is_the_virtual_loop_only_where_now_reads_it() -> None:
    class OwnNow(VirtualClock):
        def now(self) -> float:
            return 1.0

    class OwnTime(VirtualTimeEventLoop):
        def time(self) -> float:
            return 2.0

    loop = VirtualTimeEventLoop(start=3.0)
    other = OwnTime()
    try:
        assert stamp_loop(VirtualClock(), loop) is loop
        assert stamp_loop(OwnNow(), loop) is None
        assert stamp_loop(VirtualClock(), other) is None
        assert stamp_loop(VirtualClock(), None) is None
    finally:
        loop.close()
        other.close()


@settings(max_examples=100, deadline=None)
@given(
    actions=st.dictionaries(
        st.sampled_from(["move", "pick", "drop"]), st.lists(NAMES, max_size=2), min_size=1
    ),
    start=st.sampled_from([0.0, 7.5]),
)
def test_statuses_made_from_the_kept_fields_are_performer_statuses(
    actions: dict[str, list[str]], start: float
) -> None:
    """Started, a performer makes its statuses from fields kept at start; they must be
    what ``performer_statuses`` makes, field by field and in the same order."""

    async def main() -> None:
        clock = VirtualClock(start=start)
        hub = Hub(InProcessTransport(), clock)
        await hub.start()
        sent: list[Any] = []
        hub.subscribe(Topics.PERFORMERS_STATUS, sent.append)
        p = Plain(PerformerContext(hub, clock), "p", actions)
        await p.start()
        await asyncio.sleep(0.25)
        sent.clear()
        p._publish_status()
        await asyncio.sleep(0)
        expected = performer_statuses(clock.now(), p.state, p.actions.items(), "p")
        assert sent == expected
        assert [list(vars(m).items()) for m in sent] == [list(vars(m).items()) for m in expected]
        await p.stop()
        await hub.close()

    run(main(), VirtualClock(start=start))
