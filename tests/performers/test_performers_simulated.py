"""The simulated performer: durations, seeded outcomes, feedback, fault injection."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from plansys_bridge.clock import WallClock, run
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionPerformerStatus, ExecutionType, Topics
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import ActionGoal, PerformerContext
from plansys_bridge.performers.simulated import FaultPlan, SimulatedPerformer, SimulatedSettings


def _sim(hub: Hub, name: str = "sim", **kw: Any) -> SimulatedPerformer:
    actions = kw.pop("actions", {"move": [], "cook": []})
    return SimulatedPerformer(PerformerContext(hub, hub.clock), name, actions, **kw)


def _run_actions(
    hub: Hub,
    perf: SimulatedPerformer,
    calls: list[tuple[str, tuple[str, ...]]],
    policy: AuctionPolicy | None = None,
) -> list[tuple[float, ActionOutcome]]:
    async def main() -> list[tuple[float, ActionOutcome]]:
        await hub.start()
        await perf.start()
        loop = asyncio.get_running_loop()
        out = []
        for i, (action, args) in enumerate(calls):
            start = loop.time()
            outcome = await ActionClient(hub, action, args, request_id=str(i), policy=policy).run()
            out.append((round(loop.time() - start, 6), outcome))
        await perf.stop()
        await hub.close()
        return out

    return run(main(), hub.clock)


def test_durations_hint_then_full_text_then_action_then_default(virtual_hub: Hub) -> None:
    hints = {("move", ("r1", "b", "c")): 9.0}
    perf = _sim(
        virtual_hub,
        durations={"move": 3.8, "(move r1 a b)": 1.5},
        default_duration=21.0,
        duration_hint=lambda g: hints.get((g.action, g.arguments)),
    )
    results = _run_actions(
        virtual_hub,
        perf,
        [
            ("move", ("r1", "a", "b")),
            ("move", ("r1", "b", "c")),
            ("move", ("r2", "a", "b")),
            ("cook", ("r1",)),
        ],
    )
    assert [d for d, _ in results] == [1.5, 9.0, 3.8, 21.0]
    assert all(o.success for _, o in results)


def test_success_rate_is_seeded(virtual_hub: Hub) -> None:
    def outcomes(seed: int) -> list[bool]:
        hub = Hub(InProcessTransport(), type(virtual_hub.clock)())
        perf = _sim(hub, success_rate=0.5, seed=seed, default_duration=0.1, feedback_period=None)
        return [o.success for _, o in _run_actions(hub, perf, [("move", ("r1",))] * 40)]

    first = outcomes(4)
    assert first == outcomes(4)
    assert 5 < sum(first) < 35
    assert first != outcomes(5)


def test_failure_status_says_it_was_simulated(virtual_hub: Hub) -> None:
    perf = _sim(virtual_hub, success_rate=0.0, default_duration=2.0)
    [(_, outcome)] = _run_actions(virtual_hub, perf, [("move", ("r1", "a"))])
    assert not outcome.success
    assert outcome.status == "(move r1 a) failed (simulated, success rate 0)"
    assert outcome.completion == pytest.approx(0.5)
    assert perf.stats["failed"] == 1


def test_feedback_rate(virtual_hub: Hub, hub_recorder: Any) -> None:
    perf = _sim(virtual_hub, durations={"cook": 2.0}, feedback_period=0.5)

    async def main() -> Any:
        await virtual_hub.start()
        rec = hub_recorder(virtual_hub)
        await perf.start()
        await ActionClient(virtual_hub, "cook", ["r1"], request_id="c").run()
        await perf.stop()
        return rec

    rec = run(main(), virtual_hub.clock)
    feedback = [(t, m.completion) for t, m in rec.messages if m.type is ExecutionType.FEEDBACK]
    assert feedback == [(0.5, 0.25), (1.0, 0.5), (1.5, 0.75)]


def test_a_dead_performer_goes_silent_and_revives(virtual_hub: Hub, hub_recorder: Any) -> None:
    perf = _sim(virtual_hub, default_duration=4.0, faults={"revive_after": 10.0, "die_at": 0.25})
    perf.die_during_next()

    async def main() -> tuple[Any, tuple[ActionOutcome, ActionOutcome]]:
        await virtual_hub.start()
        rec = hub_recorder(virtual_hub, (Topics.ACTIONS_HUB, Topics.PERFORMERS_STATUS))
        await perf.start()
        policy = AuctionPolicy(liveness_timeout=3.0, reauctions=0)
        lost = await ActionClient(virtual_hub, "move", ["r1"], request_id="a", policy=policy).run()
        assert perf.dead
        await asyncio.sleep(10.0)
        assert not perf.dead and not perf.busy
        again = await ActionClient(virtual_hub, "move", ["r1"], request_id="b").run()
        await perf.stop()
        return rec, (lost, again)

    rec, (lost, again) = run(main(), virtual_hub.clock)
    assert not lost.success and lost.lost_performers == ("sim",)
    assert lost.status.endswith("re-auction disabled")
    assert again.success
    silent = [
        t
        for t, m in rec.messages
        if 1.0 < t < 11.0 and getattr(m, "type", None) is not ExecutionType.CANCEL
    ]
    assert silent == []  # nothing at all from the dead node between dying and reviving
    status_times = [t for t, m in rec.messages if isinstance(m, ActionPerformerStatus)]
    assert 11.0 in status_times
    assert perf.stats["died"] == 1


def test_seeded_fault_rates(virtual_hub: Hub) -> None:
    perf = _sim(
        virtual_hub,
        default_duration=1.0,
        feedback_period=None,
        seed=11,
        faults=FaultPlan(lose_finish_rate=0.3),
    )
    policy = AuctionPolicy(liveness_timeout=2.0, reauctions=0)
    results = _run_actions(virtual_hub, perf, [("move", ("r1",))] * 30, policy)
    lost = sum(1 for _, o in results if o.lost_performers)
    assert lost == perf.stats["lost_finish"]
    assert 3 <= lost <= 20


def test_never_answer_and_set_unresponsive(virtual_hub: Hub) -> None:
    perf = _sim(virtual_hub, faults={"never_answer": True})
    assert not perf.accepts(ActionGoal("move", ("r1",), "x"))
    perf.set_unresponsive(False)
    assert perf.accepts(ActionGoal("move", ("r1",), "x"))


def test_time_scale_shortens_wall_clock_actions() -> None:
    hub = Hub(InProcessTransport(), WallClock(time_scale=0.01))
    perf = _sim(hub, durations={"cook": 21.0}, feedback_period=5.0)
    [(seconds, outcome)] = _run_actions(hub, perf, [("cook", ("r1",))])
    assert outcome.success
    assert seconds >= 0.21 - 1e-3  # loop (real) seconds: 21 mission s x 0.01


def test_from_config(virtual_hub: Hub) -> None:
    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    [perf] = SimulatedPerformer.from_config(
        {
            "kind": "simulated",
            "name": "r1_nav",
            "actions": {"move": ["r1"]},
            "durations": {"move": 3.8},
            "default_duration": 2,
            "success_rate": 0.9,
            "seed": 3,
            "feedback_period": None,
            "faults": {"die_rate": 0.01, "lose_finish_rate": 0.02, "revive_after": 30},
        },
        ctx,
    )
    assert isinstance(perf, SimulatedPerformer)
    assert perf.durations == {"move": 3.8}
    assert perf.feedback_period is None
    assert perf.faults == FaultPlan(die_rate=0.01, lose_finish_rate=0.02, revive_after=30)


@pytest.mark.parametrize(
    ("settings", "key"),
    [
        ({"durations": {"move": -1}}, "p.durations.move"),
        ({"durations": [3.8]}, "p.durations"),
        ({"success_rate": 1.5}, "p.success_rate"),
        ({"default_duration": "long"}, "p.default_duration"),
        ({"feedback_period": 0}, "p.feedback_period"),
        ({"seed": 1.5}, "p.seed"),
        ({"faults": {"die_rate": 2}}, "p.faults.die_rate"),
        ({"faults": {"dye_rate": 0.1}}, "p.faults.dye_rate"),
        ({"faults": "often"}, "p.faults"),
        ({"duration": 3}, "p.duration"),
    ],
)
def test_from_config_errors(virtual_hub: Hub, settings: dict[str, Any], key: str) -> None:
    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    entry = {"kind": "simulated", "name": "x", "actions": {"move": []}, **settings}
    with pytest.raises(ConfigError) as err:
        SimulatedPerformer.from_config(entry, ctx, key="p")
    assert err.value.key == key


def test_settings_are_the_declared_model_checked_at_parse() -> None:
    """The entry is checked without building anything (what the mission loader does),
    durations keys included: a misspelt action would never apply."""
    assert SimulatedPerformer.Settings is SimulatedSettings
    entry = {"kind": "simulated", "name": "x", "actions": {"move": []}}
    parsed = SimulatedPerformer.parse_config({**entry, "faults": None}, key="p")
    assert parsed.settings == SimulatedSettings()
    with pytest.raises(ConfigError) as err:
        SimulatedPerformer.parse_config({**entry, "durations": {"mvoe": 2}}, key="p")
    assert err.value.key == "p.durations.mvoe"
    assert "not one of this performer's actions (move)" in str(err.value)
    ok = SimulatedPerformer.parse_config({**entry, "durations": {"(Move r1 a b)": 2}}, key="p")
    assert ok.settings.durations == {"(Move r1 a b)": 2}


def test_keywords_go_through_the_same_model(virtual_hub: Hub) -> None:
    with pytest.raises(ConfigError) as err:
        _sim(virtual_hub, success_rate=1.5)
    assert err.value.key == "success_rate"
    with pytest.raises(ConfigError) as err:
        _sim(virtual_hub, faults={"die_at": 1.0})
    assert err.value.key == "faults.die_at"
    perf = _sim(virtual_hub, durations={" Move ": 2}, faults=FaultPlan(never_answer=True))
    assert perf.durations == {"move": 2.0}
    assert perf.unresponsive


def test_settings_and_keywords_together_are_refused(virtual_hub: Hub) -> None:
    with pytest.raises(TypeError, match="not both"):
        _sim(virtual_hub, settings=SimulatedSettings(), seed=3)


@pytest.mark.parametrize(
    ("build", "key", "message"),
    [
        (lambda: FaultPlan(die_rate=2), "die_rate", "less than or equal to 1, got 2"),
        (lambda: FaultPlan(die_at=1.0), "die_at", "less than 1, got 1.0"),
        (lambda: FaultPlan(revive_after=-1), "revive_after", "greater than or equal to 0"),
        (lambda: FaultPlan(dye_rate=0.1), "dye_rate", "unknown key (allowed: die_at, die_rate"),
        (lambda: SimulatedSettings(success_rate=2), "success_rate", "less than or equal to 1"),
        (
            lambda: SimulatedSettings(faults={"lose_finish_rate": -0.5}),
            "faults.lose_finish_rate",
            "greater than or equal to 0",
        ),
    ],
)
def test_direct_construction_with_a_bad_value_is_a_config_error(
    build: Any, key: str, message: str
) -> None:
    """Code building the settings gets the project's error naming the field, not
    pydantic's ValidationError."""
    with pytest.raises(ConfigError) as err:
        build()
    assert err.value.key == key, str(err.value)
    assert message in str(err.value)


def test_mission_validation_keeps_the_key_path_of_nested_faults() -> None:
    """Validating an entry (what the mission loader does) does not run the direct
    constructor: a nested fault's error still names the whole key path."""
    entry = {"kind": "simulated", "name": "x", "actions": {"move": []}}
    with pytest.raises(ConfigError) as err:
        SimulatedPerformer.parse_config({**entry, "faults": {"die_at": 2}}, key="performers[4]")
    assert err.value.key == "performers[4].faults.die_at"
    assert FaultPlan(die_rate=0.25, revive_after=3).die_rate == 0.25
