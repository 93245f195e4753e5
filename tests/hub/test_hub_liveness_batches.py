"""The liveness table takes a performer's statuses of one change of state in one call
(``on_statuses``): it must end as the table taking one message at a time (written out
here as the reference, as ``on_status`` was before batches), watchers told of the same
statuses in the same order, and a hub must feed it so."""

from __future__ import annotations

import asyncio
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.liveness import LivenessTable
from plansys_bridge.hub.messages import (
    ActionPerformerStatus,
    PerformerState,
    Topics,
    performer_statuses,
)
from plansys_bridge.hub.transport import InProcessTransport

STATES = st.sampled_from(list(PerformerState))
BATCHES = st.lists(
    st.tuples(
        st.sampled_from(["n1", "n2"]),
        STATES,
        st.lists(st.sampled_from(["move", "pick"]), min_size=1, max_size=2, unique=True),
        st.booleans(),  # a foreign message in the batch too
    ),
    max_size=8,
)


class Reference(LivenessTable):
    """A heartbeat at a time, each stamped with the loop's time when it is taken."""

    def on_statuses(self, messages: Any) -> None:
        for msg in messages:
            if not isinstance(msg, ActionPerformerStatus):
                continue
            self.heartbeats += 1
            key = (msg.node_name, msg.action)
            previous = self._states.get(key)
            self._states[key] = msg.state
            if msg.state is PerformerState.RUNNING:
                self._last_running[msg.node_name] = asyncio.get_running_loop().time()
            elif msg.state is PerformerState.READY and previous is PerformerState.RUNNING:
                for callback in list(self._watchers.get(msg.action, ())):
                    callback(msg)


def _table_state(table: LivenessTable, told: list[tuple[str, object]]) -> dict[str, Any]:
    return {
        "heartbeats": table.heartbeats,
        "states": {(n, a): table.state(n, a) for n in ("n1", "n2") for a in ("move", "pick")},
        "running": {n: table.last_running(n) for n in ("n1", "n2")},
        "told": told,
    }


async def _feed(batches: list[Any], together: bool) -> dict[str, Any]:
    table = LivenessTable() if together else Reference()
    told: list[tuple[str, object]] = []
    for action in ("move", "pick"):
        table.watch(action, lambda m, a=action: told.append((a, m)))
    loop = asyncio.get_running_loop()
    for node, state, actions, foreign in batches:
        statuses: list[object] = list(
            performer_statuses(loop.time(), state, [(a, ()) for a in actions], node)
        )
        if foreign:
            statuses.insert(1, "not a status")
        if together:
            table.on_statuses(statuses)
        else:
            for msg in statuses:
                table.on_status(msg)
        await asyncio.sleep(0.5)
    return _table_state(table, told)


@settings(max_examples=200, deadline=None)
@given(batches=BATCHES)
def test_on_statuses_ends_as_one_status_at_a_time(batches: list[Any]) -> None:
    together = run(_feed(batches, True), VirtualClock())
    one_by_one = run(_feed(batches, False), VirtualClock())
    assert together == one_by_one


async def _through_hub(batches: list[Any]) -> dict[str, Any]:
    clock = VirtualClock()
    hub = Hub(InProcessTransport(), clock)
    await hub.start()
    table = hub.liveness
    told: list[tuple[str, object]] = []
    for action in ("move", "pick"):
        table.watch(action, lambda m, a=action: told.append((a, m)))
    for node, state, actions, _foreign in batches:
        hub.publish_many(
            Topics.PERFORMERS_STATUS,
            performer_statuses(clock.now(), state, [(a, ()) for a in actions], node),
        )
        await asyncio.sleep(0.5)
    result = _table_state(table, told)
    await hub.close()
    return result


@settings(max_examples=100, deadline=None)
@given(batches=BATCHES)
def test_a_hub_feeds_its_table_as_statuses_one_by_one_would(batches: list[Any]) -> None:
    plain = [(n, s, a, False) for n, s, a, _ in batches]
    assert run(_through_hub(plain), VirtualClock()) == run(_feed(plain, False), VirtualClock())


def test_a_hub_hands_a_change_of_state_to_its_table_in_one_call() -> None:
    calls: list[int] = []

    class Counted(LivenessTable):
        def on_statuses(self, messages: Any) -> None:
            calls.append(len(messages))
            super().on_statuses(messages)

    async def main() -> None:
        import plansys_bridge.hub.hub as hub_module

        clock = VirtualClock()
        hub = Hub(InProcessTransport(), clock)
        original = hub_module.LivenessTable
        hub_module.LivenessTable = Counted  # type: ignore[misc]
        try:
            table = hub.liveness
        finally:
            hub_module.LivenessTable = original  # type: ignore[misc]
        await hub.start()
        served = [("move", ()), ("pick", ())]
        hub.publish_many(
            Topics.PERFORMERS_STATUS,
            performer_statuses(0.0, PerformerState.RUNNING, served, "n1"),
        )
        await asyncio.sleep(0)
        assert calls == [2]
        assert table.state("n1", "pick") is PerformerState.RUNNING
        await hub.close()

    run(main(), VirtualClock())


def test_the_hub_makes_one_table_until_closed_and_no_other_name() -> None:
    async def main() -> None:
        hub = Hub(InProcessTransport(), VirtualClock())
        await hub.start()
        table = hub.liveness
        assert hub.liveness is table
        try:
            hub.no_such_thing  # type: ignore[attr-defined]  # noqa: B018
        except AttributeError as exc:
            assert "no_such_thing" in str(exc)
        else:
            raise AssertionError("an unknown attribute was found")
        await hub.close()
        assert "liveness" not in vars(hub)  # made again on next use (as before: none closed)

    run(main(), VirtualClock())


@settings(max_examples=100, deadline=None)
@given(order=st.permutations(range(3)), watched=st.lists(st.integers(0, 2), min_size=1))
def test_unwatching_in_any_order_leaves_exactly_the_others(
    order: list[int], watched: list[int]
) -> None:
    async def main() -> None:
        table = LivenessTable()
        told: list[int] = []
        stops = {i: table.watch("move", lambda m, i=i: told.append(i)) for i in set(watched)}
        for i in order:
            if i in stops:
                stops.pop(i)()
                running = performer_statuses(0.0, PerformerState.RUNNING, [("move", ())], "n")
                ready = performer_statuses(0.0, PerformerState.READY, [("move", ())], "n")
                told.clear()
                table.on_statuses(running)
                table.on_statuses(ready)
                assert told == sorted(stops)

    run(main(), VirtualClock())
