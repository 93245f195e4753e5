"""CAN logs (candump, ASC, BLF: python-can's writers, tests/data/logs/generate.py)
replayed through the real CAN performer on the virtual clock: sensing rules fire
from the recorded battery, the plan reacts; bad and truncated logs are one error
naming file and offset."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

pytest.importorskip("can")

DATA = Path(__file__).resolve().parents[1] / "data"
LOGS = DATA / "logs"

MISSION = """
name: can_replay
domain: {domain}
knowledge:
  instances: {{r2d2: robot, bb8: robot, dock: location, dock2: location, kitchen: location}}
  predicates: [(robot_at r2d2 dock), (robot_at bb8 dock2)]
  functions: [(= (travel_time r2d2 kitchen) 8), (= (travel_time bb8 kitchen) 30)]
goal: (served kitchen)
performers:
  - kind: can
    name: base_r2d2
    robot: r2d2
    actions: {{move: {{robot: 0, destination: 2}}}}
    locations: {{dock: [0, 0, 0], kitchen: {{x: 3.0, y: 1.0}}}}
    bus: {{interface: virtual, channel: replay_r2d2}}
    replay: {{log: {log}}}
  - kind: can
    name: base_bb8
    robot: bb8
    actions: {{move: {{robot: 0, destination: 2}}}}
    locations: {{dock2: [0, -1, 0], kitchen: {{x: 3.0, y: 1.0}}}}
    bus: {{interface: virtual, channel: replay_bb8}}
    simulate_base: {{x: 0.0, y: -1.0}}
sensing:
  - {{from: can, performer: base_r2d2, signal: BASE_Status.BatteryPercent,
     when: "BatteryPercent < {threshold}", clear_when: "BatteryPercent > 85",
     predicate: "(battery_low r2d2)"}}
clock: {{kind: virtual}}
timeout: 300
"""


def _write(tmp_path: Path, log: Path, threshold: float = 80) -> Path:
    path = tmp_path / "m.yaml"
    path.write_text(
        MISSION.format(domain=DATA / "sensing_bases.pddl", log=log, threshold=threshold)
    )
    return path


@pytest.mark.parametrize("name", ["base_r2d2.log", "base_r2d2.asc", "base_r2d2.blf"])
def test_the_recorded_battery_halts_the_move_and_the_plan_recovers(
    tmp_path: Path, name: str
) -> None:
    lines: list[str] = []
    report = run_mission(load_mission(_write(tmp_path, LOGS / name)), out=lines.append)
    assert report.success, report.summary()
    assert report.result is not None and report.result.replans == 1
    first, second = report.result.actions
    assert first.text == "(move r2d2 dock kitchen)" and first.status == ActionStatus.FAILED
    assert second.text == "(move bb8 dock2 kitchen)" and second.status == ActionStatus.SUCCEEDED
    (sensed,) = [e for e in report.events_applied if "sensed" in e]
    # the generated recording crosses 80 % after about 1.3 m, a few seconds in
    t = float(sensed.split()[0].removeprefix("t="))
    assert 1.0 < t < 8.0, sensed
    assert first.end == pytest.approx(t, abs=0.2)


def test_the_replayed_base_arrives_when_nothing_stops_it(tmp_path: Path) -> None:
    report = run_mission(load_mission(_write(tmp_path, LOGS / "base_r2d2.asc", 10)), out=None)
    assert report.success, report.summary()
    assert report.result is not None and report.result.replans == 0
    (move,) = report.result.actions
    assert move.text == "(move r2d2 dock kitchen)" and move.status == ActionStatus.SUCCEEDED


def _cut(src: Path, dst: Path, keep: float) -> Path:
    data = src.read_bytes()
    dst.write_bytes(data[: int(len(data) * keep)])
    return dst


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("base_r2d2.log", r"cut\.log:\d+ \(byte offset \d+\): (the log is truncated|not a frame)"),
        ("base_r2d2.asc", r"cut\.asc:\d+ \(byte offset \d+\): the log is truncated"),
        ("base_r2d2.blf", r"cut\.blf \(byte offset \d+\): the log is truncated"),
    ],
)
def test_a_truncated_log_is_one_error_naming_file_and_offset(
    tmp_path: Path, name: str, expected: str
) -> None:
    log = _cut(LOGS / name, tmp_path / f"cut{Path(name).suffix}", 0.6)
    with pytest.raises(ConfigError, match=r"performers\[0\]\.replay\.log: .*" + expected):
        run_mission(load_mission(_write(tmp_path, log)), out=None)


def test_a_garbled_line_names_its_line_and_offset(tmp_path: Path) -> None:
    lines = (LOGS / "base_r2d2.log").read_text().splitlines(keepends=True)
    lines[40] = "(12.5) can0 this is not a frame\n"
    log = tmp_path / "bad.log"
    log.write_text("".join(lines))
    offset = sum(len(x) for x in lines[:40])
    with pytest.raises(ConfigError) as info:
        run_mission(load_mission(_write(tmp_path, log)), out=None)
    assert f"bad.log:41 (byte offset {offset}): not a frame of this log format" in str(info.value)


def test_not_a_log(tmp_path: Path) -> None:
    log = tmp_path / "x.blf"
    log.write_bytes(b"\x00\xff" * 40)
    with pytest.raises(ConfigError, match=r"x\.blf \(byte offset 0\): not a BLF file"):
        run_mission(load_mission(_write(tmp_path, log)), out=None)
    other = tmp_path / "x.trc"
    other.write_text("")
    with pytest.raises(ConfigError, match=r"unknown log format '\.trc'"):
        run_mission(load_mission(_write(tmp_path, other)), out=None)
