"""Rule logic and timing: hysteresis decided sample by sample, rate limits on the
virtual clock, every write through the problem expert (one notification each)."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import pytest

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.sensing.engine import RuleRunner
from plansys_bridge.sensing.expressions import parse_expression
from plansys_bridge.sensing.load import LoadedRule
from plansys_bridge.sensing.rules import Change, RuleConfig, RuleLogic
from plansys_bridge.sensing.source import SensingSource

DOMAIN = (Path(__file__).resolve().parents[1] / "data" / "sensing_bases.pddl").read_text()


def _logic(when: str, clear_when: str | None = None) -> RuleLogic:
    return RuleLogic(
        predicate="(battery_low r2d2)",
        function=None,
        when=parse_expression(when),
        clear_when=parse_expression(clear_when) if clear_when else None,
        value=None,
    )


def test_hysteresis_sets_below_and_clears_only_above_the_upper_threshold() -> None:
    logic = _logic("b < 25", "b > 35")
    seen = [logic.decide({"b": b}) for b in (50, 40, 30, 24, 20, 30, 34, 36, 30, 24)]
    assert [c.text() if c else None for c in seen] == [
        "-(battery_low r2d2)",  # the first deciding sample is always said
        None,
        None,
        "+(battery_low r2d2)",
        None,
        None,  # between the thresholds: no change either way
        None,
        "-(battery_low r2d2)",
        None,
        "+(battery_low r2d2)",
    ]


def test_without_clear_when_the_predicate_follows_when() -> None:
    logic = _logic("fault != 0")
    changes = [logic.decide({"fault": f}) for f in (1, 1, 0, 0, 4)]
    assert [c.value if c else None for c in changes] == [True, None, False, None, True]


def test_between_thresholds_at_start_nothing_is_decided() -> None:
    logic = _logic("b < 25", "b > 35")
    assert logic.decide({"b": 30}) is None and logic.active is None


def test_function_rules_gated_by_when() -> None:
    logic = RuleLogic(
        predicate=None,
        function="(battery_level r2d2)",
        when=parse_expression("valid == 1"),
        clear_when=None,
        value=parse_expression("raw / 10"),
    )
    assert logic.decide({"valid": 0, "raw": 500}) is None
    assert logic.decide({"valid": 1, "raw": 500}) == Change("function", "(battery_level r2d2)", 50)


class _NoSource(SensingSource):
    def describe(self) -> str:
        return "test"


def _runner(knowledge: ProblemExpert, clock: VirtualClock, **rule: Any) -> RuleRunner:
    config = RuleConfig.model_validate({"from": "can", **rule})
    loaded = LoadedRule(
        "sensing[0]",
        config,
        _NoSource(config),
        parse_expression(config.when) if config.when else None,
        parse_expression(config.clear_when) if config.clear_when else None,
        parse_expression("b") if config.function else None,
    )
    return RuleRunner(loaded, knowledge, clock)


def _knowledge() -> ProblemExpert:
    knowledge = ProblemExpert(parse_domain(DOMAIN))
    knowledge.add_instance("r2d2", "robot")
    return knowledge


def test_every_limits_writes_and_the_last_value_arrives_when_the_interval_ends() -> None:
    knowledge = _knowledge()
    clock = VirtualClock()
    notes: list[tuple[float, dict[Any, float]]] = []
    knowledge.subscribe(lambda ch: notes.append((clock.now(), dict(ch.changed_fluents))))

    async def main() -> RuleRunner:
        runner = _runner(knowledge, clock, function="(battery_level r2d2)", every=1.0)
        for b in (90, 89, 88, 87, 86, 85, 84, 83, 82, 81):  # 10 Hz
            runner.feed({"b": b})
            await asyncio.sleep(0.1)
        await asyncio.sleep(2.0)
        return runner

    runner = run(main(), clock)
    key = ("battery_level", ("r2d2",))
    assert [(round(t, 3), values[key]) for t, values in notes] == [(0.0, 90.0), (1.0, 81.0)]
    assert runner.samples == 10 and runner.writes == 2
    assert knowledge.get_function("(battery_level r2d2)") == 81.0


def test_predicate_changes_are_rate_limited_too() -> None:
    knowledge = _knowledge()
    clock = VirtualClock()
    times: list[tuple[float, str]] = []
    knowledge.subscribe(
        lambda ch: times.append(
            (clock.now(), " ".join(f"+{a}" for a in ch.added_facts) or f"-{set(ch.removed_facts)}")
        )
    )

    async def main() -> None:
        runner = _runner(knowledge, clock, predicate="(battery_low r2d2)", when="b < 25", every=5.0)
        for b in (20, 40, 20, 40, 20):  # flapping once a second
            runner.feed({"b": b})
            await asyncio.sleep(1.0)
        await asyncio.sleep(10)

    run(main(), clock)
    # set at 0; the flaps inside the 5 s window collapse into the newest (set): no change
    assert times == [(0.0, "+(battery_low r2d2)")]
    assert knowledge.exist_predicate("(battery_low r2d2)")


def test_a_refused_write_is_logged_once_and_the_knowledge_stays(
    caplog: pytest.LogCaptureFixture,
) -> None:
    knowledge = _knowledge()
    clock = VirtualClock()
    knowledge.remove_instance("r2d2")  # the object went away after loading

    async def main() -> None:
        runner = _runner(knowledge, clock, predicate="(battery_low r2d2)", when="b < 25")
        for b in (20, 40, 20, 40):
            runner.feed({"b": b})

    run(main(), clock)
    refusals = [r for r in caplog.records if "refused" in r.getMessage()]
    # once per change refused (set, clear), not once per sample
    assert [r.getMessage().split(": ")[1] for r in refusals] == [
        "the knowledge refused +(battery_low r2d2)",
        "the knowledge refused -(battery_low r2d2)",
    ]
    assert knowledge.get_predicates() == []


def test_a_sample_without_the_field_is_logged_not_raised(caplog: pytest.LogCaptureFixture) -> None:
    knowledge = _knowledge()

    async def main() -> None:
        runner = _runner(knowledge, VirtualClock(), predicate="(battery_low r2d2)", when="b < 25")
        runner.feed({"other": 1})
        runner.feed({"other": 2})

    run(main(), VirtualClock())
    assert len([r for r in caplog.records if "no field 'b'" in r.getMessage()]) == 1
