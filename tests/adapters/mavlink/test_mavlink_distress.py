"""Live supervision reads the HEARTBEAT's system state: ArduPilot reports CRITICAL
while a failsafe holds (``any_failsafe_triggered``) and may send that HEARTBEAT
before the STATUSTEXT naming the failsafe. Messages are packed and parsed by
pymavlink, as they would arrive over a link."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from plansys_bridge_adapters.mavlink.errors import VehicleFault
from plansys_bridge_adapters.mavlink.supervision import EXPLAIN_WAIT
from plansys_bridge_adapters.mavlink.vehicle import MavlinkVehicle

mavlink2 = pytest.importorskip("pymavlink.dialects.v20.ardupilotmega")

GUIDED = 4
ACTIVE, CRITICAL, EMERGENCY = (
    mavlink2.MAV_STATE_ACTIVE,
    mavlink2.MAV_STATE_CRITICAL,
    mavlink2.MAV_STATE_EMERGENCY,
)
ARMED = mavlink2.MAV_MODE_FLAG_SAFETY_ARMED | mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED


class Autopilot:
    """Packs what an ArduCopter would send and parses it back, byte for byte."""

    def __init__(self) -> None:
        self.tx = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        self.rx = mavlink2.MAVLink(None)

    def _wire(self, msg: Any) -> Any:
        parsed = self.rx.parse_buffer(msg.pack(self.tx))
        assert parsed is not None and len(parsed) == 1
        return parsed[0]

    def heartbeat(self, state: int) -> Any:
        return self._wire(
            mavlink2.MAVLink_heartbeat_message(
                mavlink2.MAV_TYPE_QUADROTOR,
                mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
                ARMED,
                GUIDED,
                state,
                3,
            )
        )

    def statustext(self, text: str, severity: int = mavlink2.MAV_SEVERITY_CRITICAL) -> Any:
        return self._wire(mavlink2.MAVLink_statustext_message(severity, text.encode()))


async def _supervised(feed: list[tuple[float, Any]], before: list[Any] = ()) -> str | None:  # type: ignore[assignment]
    """Feed the messages (delay in seconds, message) during a supervised 1.5 s action;
    the fault's text, or None when the action ran to its end."""
    vehicle = MavlinkVehicle("tcp:127.0.0.1:5760")
    for msg in before:
        vehicle.receive(msg)
    vehicle.expected_modes = frozenset({GUIDED})

    async def feeder() -> None:
        for delay, msg in feed:
            await asyncio.sleep(delay)
            vehicle.receive(msg)

    task = asyncio.create_task(feeder())
    try:
        await vehicle.supervise(asyncio.sleep(1.5))
        return None
    except VehicleFault as exc:
        assert exc.took_over
        return str(exc)
    finally:
        task.cancel()


def test_a_heartbeat_turning_critical_ends_the_action() -> None:
    ap = Autopilot()
    text = asyncio.run(_supervised([(0.1, ap.heartbeat(ACTIVE)), (0.1, ap.heartbeat(CRITICAL))]))
    assert text is not None and "vehicle state CRITICAL (HEARTBEAT)" in text, text


def test_emergency_is_named() -> None:
    ap = Autopilot()
    text = asyncio.run(_supervised([(0.1, ap.heartbeat(EMERGENCY))], [ap.heartbeat(ACTIVE)]))
    assert text is not None and "vehicle state EMERGENCY" in text, text


def test_the_failsafe_statustext_following_the_heartbeat_names_the_cause() -> None:
    ap = Autopilot()
    feed = [(0.1, ap.heartbeat(CRITICAL)), (EXPLAIN_WAIT / 3, ap.statustext("Battery Failsafe"))]
    text = asyncio.run(_supervised(feed, [ap.heartbeat(ACTIVE)]))
    assert text == "tcp:127.0.0.1:5760: failsafe: 'Battery Failsafe'", text


def test_a_state_critical_before_the_action_or_cleared_at_once_is_not_a_fault() -> None:
    ap = Autopilot()
    # already CRITICAL when the action began: only a change is news
    assert (
        asyncio.run(_supervised([(0.1, ap.heartbeat(CRITICAL))], [ap.heartbeat(CRITICAL)])) is None
    )
    # CRITICAL for one HEARTBEAT, ACTIVE again before the explaining wait is over
    feed = [(0.1, ap.heartbeat(CRITICAL)), (EXPLAIN_WAIT / 3, ap.heartbeat(ACTIVE))]
    assert asyncio.run(_supervised(feed, [ap.heartbeat(ACTIVE)])) is None
