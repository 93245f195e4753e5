"""CanBasePerformer through the hub's ActionClient, against the base double (virtual time)."""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable, Coroutine
from typing import Any

import pytest
from can_rig import LOCATIONS, Rig, base_entry, can_rig
from plansys_bridge_adapters.can.bus import BusOpenError
from plansys_bridge_adapters.can.dbc import VelocityCommand
from plansys_bridge_adapters.can.double import BaseDoubleConfig
from plansys_bridge_adapters.can.performer import CanBasePerformer

from plansys_bridge.clock import WallClock, run
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import PerformerState, Topics
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.performers.base import ActionGoal, PerformerContext
from plansys_bridge.performers.registry import load_performer_kind

Scenario = Callable[[Rig], Coroutine[Any, Any, None]]


def play(hub: Hub, channel: str, scenario: Scenario, **rig_kw: Any) -> None:
    async def main() -> None:
        async with can_rig(hub, channel, **rig_kw) as rig:
            await scenario(rig)

    run(main(), hub.clock)


async def move(
    rig: Rig, destination: str, feedback: list[tuple[float, str]] | None = None, robot: str = "r2d2"
) -> ActionOutcome:
    client = ActionClient(
        rig.hub, "move", [robot, "somewhere", destination], policy=AuctionPolicy(give_up_after=3.0)
    )
    return await client.run(
        (lambda completion, status: feedback.append((completion, status)))
        if feedback is not None
        else None
    )


async def moving(rig: Rig, seconds: float) -> tuple[ActionClient, asyncio.Task[ActionOutcome]]:
    """Start ``(move r2d2 dock kitchen)`` and let it drive for ``seconds``."""
    client = ActionClient(rig.hub, "move", ["r2d2", "dock", "kitchen"])
    task = asyncio.get_running_loop().create_task(client.run())
    await rig.clock.sleep(seconds)
    return client, task


async def settle(rig: Rig, seconds: float = 1.0) -> None:
    await rig.clock.sleep(seconds)


def assert_base_stopped(rig: Rig) -> None:
    assert not rig.double.model.moving
    last = rig.double.last_command
    assert last is not None and last.linear == 0.0 and last.angular == 0.0


def test_entry_point_names_the_class() -> None:
    assert load_performer_kind("can") is CanBasePerformer


def test_moves_to_named_locations_with_progress(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        for name in ("kitchen", "bedroom", "dock"):
            feedback: list[tuple[float, str]] = []
            outcome = await move(rig, name, feedback)
            assert outcome.success, outcome.status
            assert outcome.status.startswith(f"arrived at {name}")
            assert outcome.performer == "base_r2d2"
            spec = LOCATIONS[name]
            x, y = (spec[0], spec[1]) if isinstance(spec, list) else (spec["x"], spec["y"])
            model = rig.double.model
            assert math.hypot(model.x - x, model.y - y) <= 0.05
            completions = [c for c, _ in feedback]
            assert len(completions) >= 5
            assert completions == sorted(completions), "progress went backwards"
            assert completions[-1] == 1.0 and completions[0] < 0.5
            assert not model.moving
        # Commands kept the watchdog fed the whole way.
        assert rig.double.counters.watchdog_trips == 0
        assert rig.double.counters.stale_commands == 0
        assert rig.performer.state is PerformerState.READY

    play(hub, channel, scenario)


def test_final_heading_and_via_points(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        outcome = await move(rig, "bedroom")
        assert outcome.success, outcome.status
        yaw = LOCATIONS["bedroom"]["yaw"]
        assert abs(math.remainder(rig.double.model.yaw - yaw, math.tau)) <= 0.05

    play(hub, channel, scenario)


def test_only_the_configured_robot_is_served(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        outcome = await move(rig, "kitchen", robot="c3po")
        assert not outcome.success and outcome.gave_up
        assert rig.double.counters.commands == 0

    play(hub, channel, scenario)


def test_unknown_location_fails_clearly(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        outcome = await move(rig, "garage")
        assert not outcome.success
        assert "unknown location 'garage'" in outcome.status
        assert "kitchen" in outcome.status

    play(hub, channel, scenario)


def test_cancel_sends_zero_and_confirms_standstill(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        client, task = await moving(rig, 2.0)
        assert rig.double.model.moving
        client.cancel()
        outcome = await task
        assert outcome.cancelled and not outcome.success
        await settle(rig, 1.5)
        assert_base_stopped(rig)
        assert rig.double.counters.estop_commands == 0
        assert rig.performer.state is PerformerState.READY
        # The base was still short of the goal: it really stopped where it was.
        assert math.hypot(rig.double.model.x - 2.0, rig.double.model.y - 1.0) > 0.3

    play(hub, channel, scenario)


def test_cancel_engages_estop_when_the_base_does_not_stop(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        client, task = await moving(rig, 2.0)
        rig.double.silence()  # no twist can confirm the stop
        client.cancel()
        await task
        await settle(rig, 2.0)
        assert rig.double.counters.estop_commands == 1
        assert rig.double.estop_active and not rig.double.model.moving

    play(hub, channel, scenario, safety={"stop_timeout": 1.0})


def _shutdown(rig: Rig) -> None:
    """The interface disappears under the adapter (like ``ip link set can0 down``)."""
    bus = rig.performer.client.bus
    assert bus is not None
    bus.shutdown()


FAULTS: dict[str, tuple[Callable[[Rig], None], str]] = {
    "silence": (lambda rig: rig.double.silence(), "base silent on virtual:can-test-"),
    "frozen heartbeat": (lambda rig: rig.double.freeze_heartbeat(), "none with a new counter"),
    "motor fault": (lambda rig: rig.double.set_faults(motor=True), "base fault: motor fault"),
    "overcurrent": (lambda rig: rig.double.set_faults(overcurrent=True), "base fault: overcurrent"),
    "e-stop button": (lambda rig: rig.double.press_estop(), "base e-stop active"),
    "error frames": (
        lambda rig: rig.double.send_error_frames(1),
        "CAN bus error on virtual:can-test-",
    ),
    "interface gone": (lambda rig: _shutdown(rig), "CAN bus error"),
}


@pytest.mark.parametrize("fault", sorted(FAULTS))
def test_every_fault_ends_the_action_and_stops_the_base(hub: Hub, channel: str, fault: str) -> None:
    inject, expected = FAULTS[fault]

    async def scenario(rig: Rig) -> None:
        _client, task = await moving(rig, 1.5)
        assert rig.double.model.moving
        inject(rig)
        failed_at = rig.clock.now()
        outcome = await task
        assert not outcome.success and not outcome.cancelled
        assert expected in outcome.status
        assert outcome.status.startswith("(move r2d2 dock kitchen): ")
        # Detected within a heartbeat timeout plus a few control periods.
        assert rig.clock.now() - failed_at < 0.8
        await settle(rig, 1.5)
        assert not rig.double.model.moving
        # Idle again; a base that is still faulted shows as FAILURE in the heartbeat.
        lasting = fault not in ("error frames", "interface gone")
        wanted = PerformerState.FAILURE if lasting else PerformerState.READY
        assert rig.performer.state is wanted, rig.performer.base_problem

    play(hub, channel, scenario)


def test_watchdog_trip_ends_the_action(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        outcome = await move(rig, "kitchen")
        assert not outcome.success
        assert "watchdog tripped" in outcome.status
        assert rig.double.counters.watchdog_trips >= 1

    # Commands every 0.5 s against a 0.3 s watchdog: the base stops between commands.
    play(
        hub,
        channel,
        scenario,
        double=BaseDoubleConfig(watchdog_timeout=0.3),
        safety={"command_rate": 2.0},
    )


def test_blocked_base_is_reported_as_stalled(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        rig.double.block_wheels()
        outcome = await move(rig, "kitchen")
        assert not outcome.success
        assert "base not moving although commanded for 1 s" in outcome.status

    play(hub, channel, scenario, safety={"stall_timeout": 1.0})


def test_fault_present_at_start_fails_at_once(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        rig.double.set_faults(motor=True)
        await settle(rig, 0.3)
        start = rig.clock.now()
        outcome = await move(rig, "kitchen")
        assert "base fault: motor fault" in outcome.status
        assert rig.clock.now() - start < 0.5
        rig.double.set_faults(motor=False)
        outcome = await move(rig, "kitchen")
        assert outcome.success, outcome.status

    play(hub, channel, scenario)


def test_no_base_on_the_bus_fails_after_startup_timeout(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        rig.double.silence()
        await settle(rig, 1.0)
        outcome = await move(rig, "kitchen")
        assert "base heartbeat lost" in outcome.status

    play(hub, channel, scenario, safety={"startup_timeout": 1.0})


def test_garbage_on_the_bus_never_disturbs_a_move(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        async def spam() -> None:
            for i in range(40):
                rig.double.send_garbage(10, seed=i)
                await rig.clock.sleep(0.1)

        spammer = asyncio.get_running_loop().create_task(spam())
        outcome = await move(rig, "kitchen")
        await spammer
        assert outcome.success, outcome.status
        counters = rig.performer.client.counters
        assert counters.malformed_total == 400
        assert counters.error_frames == 0 and counters.bus_errors == 0

    play(hub, channel, scenario)


def test_foreign_commands_are_counted(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        rig.double.client.send_frame(VelocityCommand(0.1, 0.0, True, 1))
        await settle(rig, 0.1)
        assert rig.performer.monitor.foreign_commands == 1

    play(hub, channel, scenario)


BATTERY_DOMAIN = """
(define (domain base)
  (:requirements :typing :numeric-fluents)
  (:types robot location)
  (:predicates (robot_at ?r - robot ?l - location) (battery_low ?r - robot))
  (:functions (battery ?r - robot))
  (:action move :parameters (?r - robot ?from ?to - location)
    :precondition (robot_at ?r ?from)
    :effect (and (not (robot_at ?r ?from)) (robot_at ?r ?to))))
"""


def test_battery_goes_into_the_knowledge(hub: Hub, channel: str) -> None:
    knowledge = ProblemExpert(parse_domain(BATTERY_DOMAIN))
    knowledge.add_instance("r2d2", "robot")

    async def scenario(rig: Rig) -> None:
        await settle(rig, 0.5)
        assert knowledge.get_function("battery", ("r2d2",)) == pytest.approx(80.0, abs=0.5)
        assert not knowledge.exist_predicate("(battery_low r2d2)")
        version = knowledge.version
        await settle(rig, 1.0)  # idle drain below min_change: no writes
        assert knowledge.version == version
        rig.double.set_battery(15.0)
        await settle(rig, 0.3)
        assert knowledge.get_function("battery", ("r2d2",)) == pytest.approx(15.0, abs=0.5)
        assert knowledge.exist_predicate("(battery_low r2d2)")
        rig.double.set_battery(21.0)  # inside the hysteresis band: still low
        await settle(rig, 0.3)
        assert knowledge.exist_predicate("(battery_low r2d2)")
        rig.double.set_battery(30.0)
        await settle(rig, 0.3)
        assert not knowledge.exist_predicate("(battery_low r2d2)")

    play(
        hub,
        channel,
        scenario,
        knowledge=knowledge,
        double=BaseDoubleConfig(battery_percent=80.0),
        battery={"function": "battery", "low_predicate": "battery_low", "low_below": 20},
    )


def test_knowledge_refusing_the_battery_is_logged_not_fatal(
    hub: Hub, channel: str, caplog: pytest.LogCaptureFixture
) -> None:
    knowledge = ProblemExpert(parse_domain(BATTERY_DOMAIN))  # r2d2 is not an instance

    async def scenario(rig: Rig) -> None:
        await settle(rig, 1.0)
        outcome = await move(rig, "hall")
        assert outcome.success

    play(hub, channel, scenario, knowledge=knowledge, battery=True)
    refusals = [r for r in caplog.records if "knowledge refused" in r.getMessage()]
    assert len(refusals) == 1


def test_simulated_base_from_the_config(hub: Hub, channel: str) -> None:
    async def main() -> None:
        await hub.start()
        context = PerformerContext(hub=hub, clock=hub.clock)
        entry = base_entry(channel, simulate_base={"x": 1.0, "y": 0.0, "max_linear": 0.8})
        [performer] = CanBasePerformer.from_config(entry, context)
        assert isinstance(performer, CanBasePerformer)
        async with performer:
            assert performer.double is not None
            assert performer.double.config.limits.max_linear == 0.8
            client = ActionClient(hub, "move", ["r2d2", "hall", "dock"])
            outcome = await client.run()
            assert outcome.success, outcome.status
        assert performer.double is None
        await hub.close()

    run(main(), hub.clock)


@pytest.mark.parametrize(
    ("change", "key"),
    [
        ({"robot": None}, "performer.robot"),
        ({"actions": {"move": {"robot": 0}}}, "performer.actions.move.destination"),
        (
            {"actions": {"move": {"robot": 0, "destination": 2, "via": 1}}},
            "performer.actions.move.via",
        ),
        ({"locations": {"a": [1]}}, "performer.locations.a"),
        ({"locations": {"a": {"x": 1}}}, "performer.locations.a.y"),
        ({"bus": {"interface": "virtual", "chanel": "x"}}, "performer.bus.chanel"),
        ({"bus": {"reader": "thread"}}, "performer.bus.reader"),
        ({"bus": {"reopen_period": 0}}, "performer.bus.reopen_period"),
        ({"safety": {"heartbeat_timout": 1}}, "performer.safety.heartbeat_timout"),
        ({"safety": {"command_rate": "fast"}}, "performer.safety.command_rate"),
        ({"controller": {"max_linear": -1}}, "performer.controller.max_linear"),
        ({"controller": {"lookahed": 1}}, "performer.controller.lookahed"),
        ({"battery": {"function": 3}}, "performer.battery.function"),
        (
            {"simulate_base": {"x": 0}, "bus": {"interface": "socketcan", "channel": "can0"}},
            "performer.simulate_base",
        ),
        ({"colour": "red"}, "performer.colour"),
        ({"dbc": "missing.dbc"}, "performer.dbc"),
    ],
)
def test_config_errors_name_the_key(
    hub: Hub, channel: str, change: dict[str, Any], key: str
) -> None:
    entry = base_entry(channel, **change)
    entry = {k: v for k, v in entry.items() if v is not None}
    with pytest.raises(ConfigError) as info:
        CanBasePerformer.from_config(entry, PerformerContext(hub=hub, clock=hub.clock))
    assert info.value.key == key, str(info.value)


def test_misspelt_interface_is_refused_at_load(hub: Hub) -> None:
    context = PerformerContext(hub=hub, clock=hub.clock)
    entry = base_entry("can0", bus={"interface": "socketcann", "channel": "can0"})
    with pytest.raises(ConfigError) as err:
        CanBasePerformer.from_config(entry, context)
    assert err.value.key == "performer.bus.interface"
    assert "did you mean 'socketcan'?" in str(err.value)


def test_unopenable_interface_is_named(hub: Hub) -> None:
    async def main() -> None:
        context = PerformerContext(hub=hub, clock=hub.clock)
        entry = base_entry("nosuchcan0", bus={"interface": "socketcan", "channel": "nosuchcan0"})
        [performer] = CanBasePerformer.from_config(entry, context)
        with pytest.raises(BusOpenError, match="cannot open CAN bus socketcan:nosuchcan0"):
            await performer.start()

    run(main(), hub.clock)


@pytest.mark.parametrize("source", ["environment", "can.rc"])
def test_bus_without_interface_follows_python_can_config(
    hub: Hub, monkeypatch: pytest.MonkeyPatch, source: str
) -> None:
    """No ``bus.interface``: python-can's own configuration chain decides, and the
    performer says which bus that is (it used to fall back to a virtual bus silently)."""
    import can

    monkeypatch.delenv("CAN_INTERFACE", raising=False)
    monkeypatch.delenv("CAN_CHANNEL", raising=False)
    monkeypatch.setattr(can.util, "load_file_config", lambda *a, **k: {})
    if source == "environment":
        monkeypatch.setenv("CAN_INTERFACE", "socketcan")
        monkeypatch.setenv("CAN_CHANNEL", "can7")
    else:
        monkeypatch.setattr(can, "rc", {"interface": "socketcan", "channel": "can7"})
    entry = base_entry("x", bus=None)
    entry.pop("bus")
    [performer] = CanBasePerformer.from_config(entry, PerformerContext(hub=hub, clock=hub.clock))
    assert isinstance(performer, CanBasePerformer)
    assert performer.settings.bus.describe() == "socketcan:can7"
    assert "socketcan:can7 (from python-can's configuration" in performer.connects_to()


def test_bus_without_any_interface_is_an_error(hub: Hub, monkeypatch: pytest.MonkeyPatch) -> None:
    import can

    monkeypatch.delenv("CAN_INTERFACE", raising=False)
    monkeypatch.setattr(can, "rc", {})
    monkeypatch.setattr(can.util, "load_file_config", lambda *a, **k: {})
    entry = base_entry("x")
    entry.pop("bus")
    with pytest.raises(ConfigError) as err:
        CanBasePerformer.from_config(entry, PerformerContext(hub=hub, clock=hub.clock))
    assert err.value.key == "performer.bus.interface"
    assert "no CAN interface" in str(err.value)


def test_move_on_a_scaled_wall_clock_with_the_notifier_reader(channel: str) -> None:
    """Real threads and real time (4x faster): python-can's Notifier feeds the performer."""
    clock = WallClock(time_scale=0.25)
    hub = Hub(InProcessTransport(), clock)

    async def scenario(rig: Rig) -> None:
        assert rig.performer.client.bus is not None
        outcome = await move(rig, "hall")
        assert outcome.success, outcome.status
        assert math.hypot(rig.double.model.x - 1.0, rig.double.model.y) <= 0.05

    # Generous timeouts: a loaded test machine must not fake a lost heartbeat.
    play(
        hub,
        channel,
        scenario,
        safety={"heartbeat_timeout": 2.0, "odometry_timeout": 2.0, "startup_timeout": 5.0},
        bus={"interface": "virtual", "channel": channel, "reader": "notifier"},
    )


def test_bid_is_the_distance_to_the_destination(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        await settle(rig, 0.2)
        goal = ActionGoal("move", ("r2d2", "dock", "kitchen"), "bid-1")
        assert rig.performer.bid(goal) == pytest.approx(math.hypot(2.0, 1.0), abs=1e-3)
        assert rig.performer.bid(ActionGoal("move", ("r2d2", "dock", "garage"), "bid-2")) is None

    play(hub, channel, scenario)


def test_interface_reopens_after_a_driver_error(hub: Hub, channel: str) -> None:
    async def scenario(rig: Rig) -> None:
        _client, task = await moving(rig, 1.5)
        _shutdown(rig)
        outcome = await task
        assert "CAN bus error" in outcome.status
        # The next action waits for the interface to come back, then drives.
        outcome = await move(rig, "dock")
        assert outcome.success, outcome.status
        assert rig.performer.client.counters.reopens == 1

    play(hub, channel, scenario, safety={"startup_timeout": 3.0})


def test_idle_performer_reports_an_unavailable_base_as_failure(hub: Hub, channel: str) -> None:
    states: list[PerformerState] = []

    async def scenario(rig: Rig) -> None:
        rig.hub.subscribe(Topics.PERFORMERS_STATUS, lambda m: states.append(m.state))  # type: ignore[attr-defined]
        await settle(rig, 1.5)
        assert rig.performer.state is PerformerState.READY
        rig.double.press_estop()
        await settle(rig, 1.5)
        assert rig.performer.state is PerformerState.FAILURE
        assert rig.performer.base_problem == "base e-stop active"
        # An action is still taken, and fails saying why; the state stays FAILURE after.
        outcome = await move(rig, "kitchen")
        assert "base e-stop active" in outcome.status
        await settle(rig, 1.5)
        assert rig.performer.state is PerformerState.FAILURE
        rig.double.press_estop(False)
        await settle(rig, 1.5)
        assert rig.performer.state is PerformerState.READY and rig.performer.base_problem is None

    play(hub, channel, scenario)
    assert PerformerState.FAILURE in states and states[-1] is PerformerState.NOT_READY
