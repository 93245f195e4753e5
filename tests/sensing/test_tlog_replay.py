"""A recorded flight (.tlog: pymavlink's encoder, tests/data/logs/generate.py) re-run
offline through the MAVLink adapter's vehicle on the virtual clock: sensing rules
fire from the replayed BATTERY_STATUS and the plan replans; bad and truncated logs
are one error naming file and byte offset."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

pytest.importorskip("pymavlink")

ROOT = Path(__file__).resolve().parents[2]
LOG = ROOT / "tests" / "data" / "logs" / "copter1.tlog"


def _mission(tmp_path: Path, log: Path = LOG, **changes: str) -> Path:
    text = (ROOT / "configs" / "flight_replay.yaml").read_text()
    text = text.replace(
        "pddl/flight_replay_domain.pddl",
        str(ROOT / "configs" / "pddl" / "flight_replay_domain.pddl"),
    )
    text = text.replace("../bags/logs/copter1.tlog", str(log))
    for old, new in changes.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "flight.yaml"
    path.write_text(text)
    return path


def test_the_recorded_flight_reruns_and_the_low_battery_sends_the_copter_home(
    tmp_path: Path,
) -> None:
    lines: list[str] = []
    report = run_mission(load_mission(_mission(tmp_path)), out=lines.append)
    assert report.success, report.summary()
    result = report.result
    assert result is not None and result.replans == 1
    ran = [a for a in result.actions if a.status != ActionStatus.NOT_EXECUTED]
    done = [(a.text, a.status) for a in ran]
    assert done == [
        ("(takeoff copter1 pad)", ActionStatus.SUCCEEDED),
        ("(fly copter1 pad field)", ActionStatus.SUCCEEDED),
        ("(fly copter1 field pad)", ActionStatus.FAILED),
        ("(rtl copter1 pad)", ActionStatus.SUCCEEDED),
        ("(land copter1 pad)", ActionStatus.SUCCEEDED),
    ]
    # the recording's battery falls to 24 % at 45 s; each action ends with its stretch
    assert report.events_applied == ["t=45.0 +(battery_low copter1) (sensed)"]
    assert [round(a.end, 1) for a in ran] == [10.0, 40.0, 45.0, 70.0, 86.0]
    assert result.total_time == pytest.approx(86.0, abs=0.1)
    assert any(
        "sensed: +(battery_low copter1) (sensing[0] (copter1 BATTERY_STATUS))" in x for x in lines
    )


def test_a_threshold_the_flight_never_crosses_leaves_the_failsafe_to_stop_the_flight(
    tmp_path: Path,
) -> None:
    """Nothing is sensed, but the recording's switch to RTL at 45 s is a failsafe the
    flight home does not stand for: that action fails, and the plan goes on."""
    path = _mission(tmp_path, **{'"battery_remaining < 25"': '"voltages[0] < 3000"'})
    report = run_mission(load_mission(path), out=None)
    assert report.result is not None and report.result.replans == 1
    assert report.success and not report.events_applied
    (failed,) = [a for a in report.result.actions if a.status == ActionStatus.FAILED]
    assert failed.text == "(fly copter1 field pad)"
    assert "switched to RTL" in failed.message and failed.end == pytest.approx(45.3, abs=0.1)


def test_a_truncated_tlog_names_file_and_offset(tmp_path: Path) -> None:
    data = LOG.read_bytes()
    cut = tmp_path / "cut.tlog"
    cut.write_bytes(data[: len(data) // 2 + 7])
    with pytest.raises(ConfigError) as info:
        run_mission(load_mission(_mission(tmp_path, cut)), out=None)
    text = str(info.value)
    assert "performers[0].log:" in text and f"{cut} (byte offset " in text
    assert "the log is truncated" in text


def test_a_damaged_tlog_names_file_and_offset(tmp_path: Path) -> None:
    data = LOG.read_bytes()
    bad = tmp_path / "bad.tlog"
    bad.write_bytes(data[:1000] + b"garbage!" * 10 + data[1000:])
    with pytest.raises(ConfigError, match=r"bad\.tlog \(byte offset \d+\): .*CRC"):
        run_mission(load_mission(_mission(tmp_path, bad)), out=None)


def test_a_stretch_past_the_end_of_the_log_is_refused(tmp_path: Path) -> None:
    path = _mission(tmp_path, **{"start: 70, end: 86": "start: 70, end: 95"})
    with pytest.raises(
        ConfigError,
        match=r"performers\[0\]\.segments\[4\]\.end: ends at 95 s but the log lasts 90.0 s",
    ):
        run_mission(load_mission(path), out=None)
