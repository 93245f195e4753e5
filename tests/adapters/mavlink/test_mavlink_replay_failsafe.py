"""A failsafe inside a replayed flight fails the action whose stretch it falls in.

The .tlog files are written with pymavlink's encoder the way mavutil's logger stores
them (an 8-byte big-endian microsecond stamp before each packet): a copter in
GUIDED, armed, 1 Hz HEARTBEAT, that shows one of ArduPilot's failsafe signs at
t=20 s, inside the stretch of ``(fly copter1 pad field)`` (10-40 s)."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import pytest

from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

mavlink2 = pytest.importorskip("pymavlink.dialects.v20.ardupilotmega")

ROOT = Path(__file__).resolve().parents[3]
GUIDED, RTL, LAND = 4, 6, 9
ACTIVE, CRITICAL, EMERGENCY = 4, 5, 6
FAILSAFE_AT = 20.0


def _write_tlog(path: Path, sign: str) -> Path:
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    rows: list[tuple[float, Any]] = []
    for second in range(0, 91):
        t = float(second)
        after = t >= FAILSAFE_AT
        mode = GUIDED if t < 70 else LAND
        if after and sign in ("mode", "radio"):
            mode = RTL if t < 70 else LAND
        state = ACTIVE
        if after and sign in ("critical", "emergency"):
            state = CRITICAL if sign == "critical" else EMERGENCY
        base_mode = 0x01 | 0x08 | (0x80 if t < 86 else 0)
        rows.append((t, mavlink2.MAVLink_heartbeat_message(2, 3, base_mode, mode, state, 3)))
        if t == FAILSAFE_AT and sign in ("battery", "radio", "ekf"):
            text = {"battery": "Battery failsafe", "radio": "Radio Failsafe", "ekf": "EKF Failsafe"}
            rows.append((t + 0.05, mavlink2.MAVLink_statustext_message(2, text[sign].encode())))
    with path.open("wb") as f:
        for t, msg in rows:
            f.write(struct.pack(">Q", 1_700_000_000_000_000 + round(t * 1e6)) + msg.pack(mav))
    return path


def _run(tmp_path: Path, sign: str) -> Any:
    text = (ROOT / "configs" / "flight_replay.yaml").read_text()
    text = text.replace(
        "pddl/flight_replay_domain.pddl",
        str(ROOT / "configs" / "pddl" / "flight_replay_domain.pddl"),
    )
    text = text.replace("../bags/logs/copter1.tlog", str(_write_tlog(tmp_path / "f.tlog", sign)))
    path = tmp_path / "flight.yaml"
    path.write_text(text)
    report = run_mission(load_mission(path), out=None)
    assert report.result is not None
    return report


@pytest.mark.parametrize(
    ("sign", "named", "at"),
    [
        ("battery", "failsafe: 'Battery failsafe'", FAILSAFE_AT + 0.05),
        ("radio", "failsafe: 'Radio Failsafe'", FAILSAFE_AT + 0.05),
        ("ekf", "failsafe: 'EKF Failsafe'", FAILSAFE_AT + 0.05),
        ("critical", "vehicle state CRITICAL", FAILSAFE_AT + 0.3),
        ("emergency", "vehicle state EMERGENCY", FAILSAFE_AT + 0.3),
        ("mode", "switched to RTL, which (fly copter1 pad field) does not stand for", 20.3),
    ],
)
def test_a_failsafe_in_the_stretch_fails_the_action(
    tmp_path: Path, sign: str, named: str, at: float
) -> None:
    report = _run(tmp_path, sign)
    ran = [a for a in report.result.actions if a.status != ActionStatus.NOT_EXECUTED]
    assert ran[0].text == "(takeoff copter1 pad)" and ran[0].status == ActionStatus.SUCCEEDED
    fly = ran[1]
    assert fly.text == "(fly copter1 pad field)" and fly.status == ActionStatus.FAILED
    assert "failsafe at" in fly.message and "f.tlog" in fly.message
    assert named in fly.message, fly.message
    assert fly.end == pytest.approx(at, abs=0.15)


def test_without_a_failsafe_every_stretch_is_served(tmp_path: Path) -> None:
    report = _run(tmp_path, "none")
    assert report.success, report.summary()
    assert report.result.replans == 0
    assert all(a.status == ActionStatus.SUCCEEDED for a in report.result.actions)


def test_the_landing_the_action_stands_for_is_not_a_failsafe(tmp_path: Path) -> None:
    """LAND from 70 s is what (land copter1 pad) is: that stretch succeeds."""
    report = _run(tmp_path, "none")
    (land,) = [a for a in report.result.actions if a.text == "(land copter1 pad)"]
    assert land.status == ActionStatus.SUCCEEDED and land.start == pytest.approx(70.0, abs=0.1)
