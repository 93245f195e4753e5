"""MAVLink performers driven through the hub's auction, against vehicle doubles.

Every fault the issue lists must end the action with FINISH(success=false) and a
status that names the link and says why; a whole two-vehicle mission must succeed.
"""

from __future__ import annotations

import asyncio
import itertools
import re
from collections.abc import Awaitable, Callable, Mapping
from pathlib import Path
from typing import Any

import pytest
from mavlink_support import CONFIGS, SPEEDUP, build, free_port, make_hub, performer_config
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from plansys_bridge_adapters.mavlink.errors import LinkError
from plansys_bridge_adapters.mavlink.geo import distance_m, offset
from plansys_bridge_adapters.mavlink.performer import MavlinkPerformer
from pymavlink.dialects.v20 import ardupilotmega as ml

from plansys_bridge.hub.auction import ActionClient, ActionOutcome, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain

POLICY = AuctionPolicy(retry_period=0.2, give_up_after=5.0, liveness_timeout=3.0)


async def act(
    hub: Hub, action: str, *args: str, feedback: list[tuple[float, str]] | None = None
) -> ActionOutcome:
    client = ActionClient(hub, action, args, policy=POLICY)
    sink = feedback if feedback is not None else []
    return await client.run(lambda c, s: sink.append((c, s)))


def run_with(
    doubles: list[tuple[str, VehicleDouble]],
    body: Callable[[Hub, list[MavlinkPerformer]], Awaitable[None]],
    knowledge: Any = None,
    **extra: Any,
) -> None:
    """Start one performer per double, run ``body``, stop everything."""

    async def main() -> None:
        hub = make_hub()
        await hub.start()
        performers = [
            build(performer_config(name, d.url, d.params.model, **extra), hub, knowledge)
            for name, d in doubles
        ]
        try:
            for p in performers:
                await p.start()
            await asyncio.wait_for(body(hub, performers), 40)
        finally:
            for p in performers:
                await p.stop()
            await hub.close()

    asyncio.run(main())


def near(double: VehicleDouble, north: float, east: float, tol: float = 1.5) -> bool:
    s = double.state()
    return abs(s["north"] - north) <= tol and abs(s["east"] - east) <= tol


def test_copter_and_rover_missions_run_at_once(copter: VehicleDouble, rover: VehicleDouble) -> None:
    results: dict[str, list[ActionOutcome]] = {"uav1": [], "ugv1": []}
    fly_feedback: list[tuple[float, str]] = []

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        async def copter_mission() -> None:
            for action, args in [
                ("takeoff", ("uav1", "pad")),
                ("fly", ("uav1", "pad", "north_field")),
                ("fly", ("uav1", "north_field", "east_field")),
                ("land", ("uav1", "east_field")),
            ]:
                fb = fly_feedback if args[-1] == "north_field" else None
                results["uav1"].append(await act(hub, action, *args, feedback=fb))

        async def rover_mission() -> None:
            for args in [("ugv1", "yard", "gate"), ("ugv1", "gate", "yard")]:
                results["ugv1"].append(await act(hub, "drive", *args))

        await asyncio.gather(copter_mission(), rover_mission())

    run_with([("uav1", copter), ("ugv1", rover)], body)
    for outcomes in results.values():
        assert [o.success for o in outcomes] == [True] * len(outcomes), outcomes
    assert results["uav1"][0].performer == "uav1_performer"
    assert results["ugv1"][0].performer == "ugv1_performer"
    assert results["uav1"][1].status.startswith("reached north_field")
    assert results["uav1"][3].status == "landed and disarmed"
    state = copter.state()
    assert state["landed"] and not state["armed"] and state["mode"] == "LAND"
    assert near(copter, 20, 50)
    assert near(rover, 0, 0)
    completions = [c for c, _ in fly_feedback]
    assert completions and max(completions) > 0.5
    assert all(b >= a - 0.05 for a, b in itertools.pairwise(completions))
    assert any("m to north_field" in s for _, s in fly_feedback)


def test_specialised_performers_bid_only_for_their_vehicle() -> None:
    with (
        VehicleDouble("rover", speedup=SPEEDUP, ekf_delay=2.0) as r1,
        VehicleDouble("rover", speedup=SPEEDUP, ekf_delay=2.0) as r2,
    ):
        outcomes: list[ActionOutcome] = []

        async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
            outcomes.append(await act(hub, "drive", "ugv2", "yard", "gate"))
            outcomes.append(await act(hub, "drive", "ugv1", "yard", "east_field"))

        run_with([("ugv1", r1), ("ugv2", r2)], body)
        assert [o.performer for o in outcomes] == ["ugv2_performer", "ugv1_performer"]
        assert all(o.success for o in outcomes)
        assert near(r2, -30, 25) and near(r1, 20, 50)


def fly_with_fault(
    double: VehicleDouble, inject: Callable[[VehicleDouble], None], target: str = "north_field"
) -> tuple[ActionOutcome, ActionOutcome]:
    """Take off, start a flight, inject a fault once the copter is on its way."""
    out: list[ActionOutcome] = []

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        out.append(await act(hub, "takeoff", "uav1", "pad"))
        flight = asyncio.ensure_future(act(hub, "fly", "uav1", "pad", target))
        while double.state()["north"] < 5 and not flight.done():
            await asyncio.sleep(0.01)
        inject(double)
        out.append(await flight)

    run_with([("uav1", double)], body)
    return out[0], out[1]


def test_mode_change_by_someone_else_fails_the_action(copter: VehicleDouble) -> None:
    takeoff, flight = fly_with_fault(copter, lambda d: d.change_mode("LOITER"))
    assert takeoff.success
    assert not flight.success
    assert flight.status == (
        f"{copter.url}: mode changed to LOITER by someone else (expected GUIDED)"
    )


def test_failsafe_fails_the_action(copter: VehicleDouble) -> None:
    _, flight = fly_with_fault(copter, lambda d: d.failsafe("Radio"))
    assert not flight.success
    assert flight.status == f"{copter.url}: failsafe: 'Radio Failsafe'"
    assert copter.state()["mode"] == "RTL"


def test_statustext_error_fails_the_action(copter: VehicleDouble) -> None:
    _, flight = fly_with_fault(
        copter, lambda d: d.statustext("EKF3 lane switch 1", ml.MAV_SEVERITY_ERROR)
    )
    assert not flight.success
    assert flight.status == (
        f"{copter.url}: vehicle reported MAV_SEVERITY_ERROR: 'EKF3 lane switch 1'"
    )


def test_warning_statustext_does_not_fail_the_action(copter: VehicleDouble) -> None:
    _, flight = fly_with_fault(copter, lambda d: d.statustext("Wind high", ml.MAV_SEVERITY_WARNING))
    assert flight.success, flight.status


def test_wind_the_copter_cannot_fly_against_fails_the_action(copter: VehicleDouble) -> None:
    # ArduPilot reports nothing: the copter stays in GUIDED and drifts back; the
    # vehicle's own positions show it, 20 s of its time without getting closer
    _, flight = fly_with_fault(copter, lambda d: d.wind(30, from_deg=0))
    assert not flight.success
    assert flight.status.startswith(f"{copter.url}: no headway to north_field: ")
    # the window is 20 s of vehicle time; the stall is measured between the
    # positions that arrived, which a loaded machine spaces further apart
    stalled = re.search(r"for (\d+) s of vehicle time", flight.status)
    assert stalled is not None, flight.status
    assert 20 <= int(stalled.group(1)) <= 25, flight.status
    assert copter.state()["mode"] == "LAND"  # the safe mode (default)


def test_lost_heartbeat_fails_the_action(copter: VehicleDouble) -> None:
    # 1 s heartbeat timeout (conftest); the link stays silent for 200 simulated s = 5 s
    _, flight = fly_with_fault(copter, lambda d: d.drop_link(200 / SPEEDUP * SPEEDUP))
    assert not flight.success
    assert flight.status.startswith(f"{copter.url}: no HEARTBEAT for ")
    assert flight.status.endswith("(limit 1 s)")


def take_off(double: VehicleDouble) -> ActionOutcome:
    """Run ``(takeoff uav1 pad)`` with a performer on ``double``; its outcome."""
    out: list[ActionOutcome] = []

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        out.append(await act(hub, "takeoff", "uav1", "pad"))

    run_with([("uav1", double)], body)
    return out[0]


def test_refused_command_fails_the_action(copter: VehicleDouble) -> None:
    copter.refuse_next(ml.MAV_CMD_NAV_TAKEOFF, ml.MAV_RESULT_DENIED)
    out = [take_off(copter)]
    assert not out[0].success
    assert out[0].status == f"{copter.url}: MAV_CMD_NAV_TAKEOFF refused (MAV_RESULT_DENIED)"


def test_takeoff_whose_ack_is_lost_still_succeeds(copter: VehicleDouble) -> None:
    """The repeat of an obeyed take-off is refused (already off the ground), as on ArduCopter."""
    copter.lose_next_ack(ml.MAV_CMD_NAV_TAKEOFF)
    outcome = take_off(copter)
    assert outcome.success, outcome.status
    takeoffs = [c for c in copter.sim.commands_seen if c == ml.MAV_CMD_NAV_TAKEOFF]
    assert len(takeoffs) == 2
    assert outcome.status.startswith("airborne at ")  # 10 m, within the tolerance
    assert float(outcome.status.split()[2]) >= 9.0


def test_rover_stop_whose_disarm_ack_is_lost_still_succeeds(rover: VehicleDouble) -> None:
    """ArduRover answers a repeated disarm FAILED (already disarmed); the stop still succeeds."""
    out: list[ActionOutcome] = []

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        out.append(await act(hub, "drive", "ugv1", "yard", "gate"))
        rover.lose_next_ack(ml.MAV_CMD_COMPONENT_ARM_DISARM)
        out.append(await act(hub, "land", "ugv1", "gate"))

    run_with([("ugv1", rover)], body)
    assert [o.success for o in out] == [True, True], [o.status for o in out]
    assert out[1].status == "stopped and disarmed"
    assert not rover.state()["armed"]


def test_arming_is_retried_until_accepted() -> None:
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=30.0) as double:
        double.refuse_next(ml.MAV_CMD_COMPONENT_ARM_DISARM, ml.MAV_RESULT_FAILED)
        out: list[ActionOutcome] = []
        feedback: list[tuple[float, str]] = []

        async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
            out.append(await act(hub, "takeoff", "uav1", "pad", feedback=feedback))

        run_with([("uav1", double)], body)
        assert out[0].success, out[0].status
        arms = [c for c in double.sim.commands_seen if c == ml.MAV_CMD_COMPONENT_ARM_DISARM]
        assert len(arms) == 2
        statuses = [s for _, s in feedback]
        assert "waiting for the EKF to use GPS" in statuses
        assert double.state()["time"] >= 30.0


def test_guided_refused_before_the_ekf_is_set_after_it() -> None:
    with VehicleDouble(
        "copter", speedup=SPEEDUP, ekf_delay=20.0, position_modes_need_ekf=True
    ) as double:
        outcome = take_off(double)
        assert outcome.success, outcome.status
        modes = [c for c in double.sim.commands_seen if c == ml.MAV_CMD_DO_SET_MODE]
        assert len(modes) == 2  # refused before the EKF, accepted after


def test_ekf_that_never_converges_fails_with_the_reason() -> None:
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=1e6) as double:
        out: list[ActionOutcome] = []

        async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
            out.append(await act(hub, "takeoff", "uav1", "pad"))

        run_with(
            [("uav1", double)],
            body,
            timeouts={"heartbeat": 1.0, "command": 0.5, "ekf": 0.5, "arm": 1, "action": 5},
        )
        assert not out[0].success
        assert out[0].status == (
            f"{double.url}: timed out after 0.5 s waiting for the EKF "
            "to use GPS (EKF_STATUS_REPORT)"
        )


def test_flying_before_takeoff_is_refused(copter: VehicleDouble) -> None:
    out: list[ActionOutcome] = []

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        out.append(await act(hub, "fly", "uav1", "pad", "north_field"))
        out.append(await act(hub, "fly", "uav1", "pad", "atlantis"))

    run_with([("uav1", copter)], body)
    assert not out[0].success
    assert "on the ground; take off before flying to north_field" in out[0].status
    assert not out[1].success
    assert "no location 'atlantis'" in out[1].status


@pytest.mark.parametrize(
    ("model", "vehicle", "action", "hold_mode"),
    [("copter", "uav1", "fly", "LAND"), ("rover", "ugv1", "drive", "HOLD")],
)
def test_cancel_stops_in_the_default_safe_mode(
    model: str, vehicle: str, action: str, hold_mode: str
) -> None:
    with VehicleDouble(model, speedup=SPEEDUP, ekf_delay=2.0) as double:  # type: ignore[arg-type]
        out: list[ActionOutcome] = []

        async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
            if model == "copter":
                assert (await act(hub, "takeoff", vehicle, "pad")).success
            client = ActionClient(hub, action, (vehicle, "pad", "north_field"), policy=POLICY)
            task = asyncio.ensure_future(client.run())
            while double.state()["north"] < 5:
                await asyncio.sleep(0.01)
            client.cancel()
            out.append(await task)
            for _ in range(100):
                if double.state()["mode"] == hold_mode:
                    break
                await asyncio.sleep(0.02)

        run_with([(vehicle, double)], body)
        assert out[0].cancelled and not out[0].success
        state = double.state()
        assert state["mode"] == hold_mode
        assert 5 <= state["north"] < 55


def test_a_flight_after_the_safe_mode_landed_the_copter_takes_off_again() -> None:
    # a cancel lands the copter (default safe mode) while the plan still has it in the
    # air: the replanned flight takes off again instead of failing on the ground
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=2.0) as double:
        out: list[ActionOutcome] = []

        async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
            assert (await act(hub, "takeoff", "uav1", "pad")).success
            client = ActionClient(hub, "fly", ("uav1", "pad", "north_field"), policy=POLICY)
            task = asyncio.ensure_future(client.run())
            while double.state()["north"] < 5:
                await asyncio.sleep(0.01)
            client.cancel()
            assert (await task).cancelled
            while not double.state()["landed"] or double.state()["armed"]:
                await asyncio.sleep(0.05)
            out.append(await act(hub, "fly", "uav1", "pad", "north_field"))
            states.append(double.state())  # before the performer stops (and lands it)

        states: list[Mapping[str, Any]] = []
        run_with([("uav1", double)], body)
        assert out[0].success, out[0].status
        [state] = states
        assert state["armed"] and not state["landed"] and state["mode"] == "GUIDED"
        assert state["north"] > 40


def test_battery_goes_into_the_knowledge(copter: VehicleDouble) -> None:
    domain = parse_domain((CONFIGS / "pddl" / "drone_domain.pddl").read_text(), "drone_domain")
    knowledge = ProblemExpert(domain)
    knowledge.load_problem((CONFIGS / "pddl" / "drone_problem_copter.pddl").read_text())
    seen: list[tuple[float | None, bool]] = []

    def snapshot() -> None:
        seen.append(
            (
                knowledge.get_function("battery", ["uav1"]),
                knowledge.exist_predicate("(battery_low uav1)"),
            )
        )

    async def until(predicate: Callable[[], bool]) -> None:
        for _ in range(300):
            if predicate():
                return
            await asyncio.sleep(0.01)

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        knowledge.set_function("(= (battery uav1) 0)")
        await until(lambda: knowledge.get_function("battery", ["uav1"]) == 100.0)
        snapshot()
        copter.set_battery(12.0)
        await until(lambda: knowledge.exist_predicate("(battery_low uav1)"))
        snapshot()
        copter.set_battery(22.0)  # above 20 but within the 5 % hysteresis: still low
        await until(lambda: knowledge.get_function("battery", ["uav1"]) == 22.0)
        snapshot()
        copter.set_battery(26.0)
        await until(lambda: not knowledge.exist_predicate("(battery_low uav1)"))
        snapshot()

    run_with(
        [("uav1", copter)],
        body,
        knowledge=knowledge,
        telemetry={
            "battery_function": "battery",
            "low_battery_predicate": "battery_low",
            "low_battery_threshold": 20,
        },
    )
    assert seen == [(100.0, False), (12.0, True), (22.0, True), (26.0, False)]


def test_telemetry_the_domain_lacks_is_dropped_once(copter: VehicleDouble) -> None:
    domain = parse_domain((CONFIGS / "pddl" / "drone_domain.pddl").read_text(), "drone_domain")
    knowledge = ProblemExpert(domain)
    knowledge.load_problem((CONFIGS / "pddl" / "drone_problem_copter.pddl").read_text())
    out: list[ActionOutcome] = []

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        out.append(await act(hub, "takeoff", "uav1", "pad"))
        publisher = performers[0].telemetry
        assert publisher is not None
        assert publisher.disabled == {"battery_function"}

    run_with(
        [("uav1", copter)], body, knowledge=knowledge, telemetry={"battery_function": "charge"}
    )
    assert out[0].success  # a telemetry mismatch never stops the vehicle


def test_unreachable_vehicle_names_the_url(tmp_path: Path) -> None:
    url = f"tcp:127.0.0.1:{free_port()}"

    async def main() -> None:
        hub = make_hub()
        await hub.start()
        performer = build(performer_config("uav1", url, "copter", timeouts={"connect": 0.6}), hub)
        try:
            with pytest.raises(LinkError, match=f"^{url}: cannot open the link"):
                await performer.start()
        finally:
            await hub.close()

    asyncio.run(main())


def test_wrong_model_is_a_config_error(rover: VehicleDouble) -> None:
    from plansys_bridge.errors import ConfigError

    async def main() -> None:
        hub = make_hub()
        await hub.start()
        performer = build(performer_config("uav1", rover.url, "copter"), hub)
        try:
            with pytest.raises(ConfigError, match="expected a copter, the vehicle is a rover"):
                await performer.start()
        finally:
            await hub.close()

    asyncio.run(main())


def test_performer_starts_its_own_double() -> None:
    out: list[ActionOutcome] = []
    positions: list[float] = []

    async def main() -> None:
        hub = make_hub()
        await hub.start()
        config = performer_config("ugv1", "unused", "rover")
        del config["url"]
        config["double"] = {
            "model": "rover",
            "speedup": SPEEDUP,
            "ekf_delay": 2.0,
            "home": {"lat": -35.0, "lon": 149.0, "alt": 10.0},
        }
        performer = build(config, hub)
        await performer.start()
        try:
            assert performer.double is not None
            assert performer.url == performer.double.url
            out.append(await act(hub, "drive", "ugv1", "yard", "gate"))
            v = performer.vehicle
            assert v is not None and v.telemetry.position is not None
            home = offset(v.telemetry.home or v.telemetry.position, -30, 25)
            positions.append(distance_m(v.telemetry.position, home))
        finally:
            await performer.stop()
            await hub.close()

    asyncio.run(main())
    assert out[0].success, out[0].status
    assert positions[0] < 1.5


def test_rtl_and_hold_actions(copter: VehicleDouble, rover: VehicleDouble) -> None:
    out: dict[str, list[ActionOutcome]] = {"uav1": [], "ugv1": []}

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        out["uav1"].append(await act(hub, "takeoff", "uav1", "pad"))
        out["uav1"].append(await act(hub, "fly", "uav1", "pad", "gate"))
        out["uav1"].append(await act(hub, "hold", "uav1"))
        out["uav1"].append(await act(hub, "rtl", "uav1"))
        out["ugv1"].append(await act(hub, "drive", "ugv1", "yard", "east_field"))
        out["ugv1"].append(await act(hub, "hold", "ugv1"))
        out["ugv1"].append(await act(hub, "rtl", "ugv1"))
        out["ugv1"].append(await act(hub, "land", "ugv1"))

    run_with([("uav1", copter), ("ugv1", rover)], body)
    assert [o.status for o in out["uav1"][2:]] == ["holding in LOITER", "landed and disarmed"]
    assert [o.status for o in out["ugv1"][1:]] == [
        "holding in HOLD",
        "back at home, holding",
        "stopped and disarmed",
    ]
    assert all(o.success for o in out["uav1"] + out["ugv1"])
    assert near(copter, 0, 0) and copter.state()["mode"] == "RTL"
    assert near(rover, 0, 0) and not rover.state()["armed"]


def test_next_action_works_after_the_link_came_back(copter: VehicleDouble) -> None:
    out: list[ActionOutcome] = []

    async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
        out.append(await act(hub, "takeoff", "uav1", "pad"))
        copter.drop_link(2.0 * SPEEDUP)  # 2 s of silence, 1 s heartbeat timeout
        out.append(await act(hub, "fly", "uav1", "pad", "gate"))
        await asyncio.sleep(1.2)
        out.append(await act(hub, "fly", "uav1", "pad", "gate"))

    run_with([("uav1", copter)], body)
    assert [o.success for o in out] == [True, False, True], [o.status for o in out]
    assert "no HEARTBEAT" in out[1].status


def test_vehicle_restarted_is_reconnected() -> None:
    with VehicleDouble("rover", speedup=SPEEDUP, ekf_delay=2.0) as first:
        port = first.port
        out: list[ActionOutcome] = []
        second: list[VehicleDouble] = []

        async def body(hub: Hub, performers: list[MavlinkPerformer]) -> None:
            out.append(await act(hub, "drive", "ugv1", "yard", "gate"))
            await asyncio.get_running_loop().run_in_executor(None, first.stop)
            vehicle = performers[0].vehicle
            assert vehicle is not None
            while vehicle.connected:  # the reader thread reports the closed link
                await asyncio.sleep(0.01)
            out.append(await act(hub, "drive", "ugv1", "gate", "yard"))
            second.append(VehicleDouble("rover", speedup=SPEEDUP, ekf_delay=2.0, port=port).start())
            out.append(await act(hub, "drive", "ugv1", "yard", "gate"))

        try:
            run_with(
                [("ugv1", first)],
                body,
                timeouts={
                    "connect": 0.5,
                    "heartbeat": 1.0,
                    "command": 0.5,
                    "ekf": 20,
                    "arm": 10,
                    "action": 30,
                },
            )
        finally:
            for d in second:
                d.stop()
        assert [o.success for o in out] == [True, False, True], [o.status for o in out]
        assert out[1].status.startswith(f"reconnect failed: {first.url}: cannot open the link")
        assert near(second[0], -30, 25)
