"""Sensing rules in whole missions: a CAN base double's battery, read by DBC signal,
sets a predicate that halts its move and makes the executor send the other base."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import build_knowledge, load_domain, run_mission
from plansys_bridge.mission_config import load_mission

pytest.importorskip("cantools")

DATA = Path(__file__).resolve().parents[1] / "data"
CONFIGS = Path(__file__).resolve().parents[2] / "configs"

MISSION = """
name: sensing_bases
domain: {domain}
knowledge:
  instances: {{r2d2: robot, bb8: robot, dock: location, dock2: location, kitchen: location}}
  predicates: [(robot_at r2d2 dock), (robot_at bb8 dock2)]
  functions:
    - (= (travel_time r2d2 kitchen) 8)
    - (= (travel_time bb8 kitchen) 30)
goal: (served kitchen)
performers:
  - kind: can
    name: base_r2d2
    robot: r2d2
    actions: {{move: {{robot: 0, destination: 2}}}}
    locations: {locations}
    bus: {{interface: virtual, channel: sensing_r2d2}}
    simulate_base: {{x: 0.0, y: 0.0, battery_percent: {battery}}}
  - kind: can
    name: base_bb8
    robot: bb8
    actions: {{move: {{robot: 0, destination: 2}}}}
    locations: {locations}
    bus: {{interface: virtual, channel: sensing_bb8}}
    simulate_base: {{x: 0.0, y: -1.0}}
sensing:
  - {{from: can, performer: base_r2d2, signal: BASE_Status.BatteryPercent,
     when: "BatteryPercent < 80", clear_when: "BatteryPercent > 85",
     predicate: "(battery_low r2d2)"}}
  - {{from: can, performer: base_r2d2, signal: BASE_Status.BatteryPercent,
     function: "(battery_level r2d2)", every: 1.0}}
clock: {{kind: virtual}}
timeout: 300
"""


def _mission(tmp_path: Path, battery: float = 80.1, **changes: str) -> Path:
    text = MISSION.format(
        domain=DATA / "sensing_bases.pddl",
        locations=CONFIGS / "can_locations.yaml",
        battery=battery,
    )
    for old, new in changes.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "m.yaml"
    path.write_text(text)
    return path


def test_a_sensed_low_battery_halts_the_move_and_the_other_base_goes(tmp_path: Path) -> None:
    lines: list[str] = []
    report = run_mission(load_mission(_mission(tmp_path)), out=lines.append)
    assert report.success, report.summary()
    result = report.result
    assert result is not None and result.replans == 1
    first, second = result.actions
    assert first.text == "(move r2d2 dock kitchen)" and first.status == ActionStatus.FAILED
    assert "(battery_low r2d2)" in first.message
    assert second.text == "(move bb8 dock2 kitchen)" and second.status == ActionStatus.SUCCEEDED
    sensed = [e for e in report.events_applied if "sensed" in e]
    assert sensed and sensed[0].endswith("+(battery_low r2d2) (sensed)")
    assert any("sensed: +(battery_low r2d2) (sensing[0] (base_r2d2 BASE_Status" in x for x in lines)


def test_a_full_battery_lets_the_near_base_finish(tmp_path: Path) -> None:
    mission = load_mission(_mission(tmp_path, battery=95))
    report = run_mission(mission, out=None)
    assert report.success and report.result is not None
    assert report.result.replans == 0
    assert [a.text for a in report.result.actions] == ["(move r2d2 dock kitchen)"]
    assert not [e for e in report.events_applied if "sensed" in e]


def _load_error(path: Path) -> str:
    mission = load_mission(path)
    with pytest.raises(ConfigError) as info:
        build_knowledge(mission, load_domain(mission))
    return str(info.value)


def _place(text: str, anchor: str) -> str:
    """``line:col`` (1-based) of the first ``anchor`` in ``text``."""
    offset = text.index(anchor)
    line = text.count("\n", 0, offset) + 1
    return f"{line}:{offset - text.rfind(chr(10), 0, offset)}"


@pytest.mark.parametrize(
    ("old", "new", "anchor", "expected"),
    [
        # (what to break, how, where the error points, what it says)
        (
            "BASE_Status.BatteryPercent,\n     when",
            "BASE_Status.BateryPercent,\n     when",
            "BASE_Status.Batery",
            "sensing[0].signal: message BASE_Status of",
        ),
        (
            "signal: BASE_Status.BatteryPercent,\n     function",
            "signal: BASE_Stat.BatteryPercent,\n     function",
            "BASE_Stat.",
            "sensing[1].signal: no message 'BASE_Stat' in",
        ),
        (
            '"BatteryPercent < 80"',
            '"BatteryPercnt < 80"',
            "BatteryPercnt",
            "sensing[0].when: no field",
        ),
        (
            '"BatteryPercent > 85"',
            '"BatteryPercent >> 85"',
            "> 85",
            "sensing[0].clear_when: unexpected '>'",
        ),
        ("(battery_low r2d2)", "(battery_lo r2d2)", '"(battery_lo', "sensing[0].predicate:"),
        ("(battery_low r2d2)", "(battery_low c3po)", '"(battery_low c3po', "sensing[0].predicate:"),
        ("(battery_level r2d2)", "(battery r2d2)", '"(battery r2d2', "sensing[1].function:"),
        (
            "performer: base_r2d2, signal: BASE_Status.BatteryPercent,\n     function",
            "performer: base_r2d, signal: BASE_Status.BatteryPercent,\n     function",
            "base_r2d,",
            "sensing[1].performer: no performer 'base_r2d' (did you mean 'base_r2d2'?)",
        ),
        (
            "{from: can, performer: base_r2d2, signal: BASE_Status.BatteryPercent,\n     when",
            "{from: cam, performer: base_r2d2, signal: BASE_Status.BatteryPercent,\n     when",
            "cam,",
            "sensing[0].from: unknown sensing source 'cam'",
        ),
        ("every: 1.0", "evry: 1.0", "1.0}\nclock", "sensing[1].evry: unknown key for a can rule"),
    ],
)
def test_a_bad_rule_is_a_load_error_naming_file_line_column_and_key(
    tmp_path: Path, old: str, new: str, anchor: str, expected: str
) -> None:
    path = _mission(tmp_path, **{old: new})
    text = _load_error(path)
    where = f"{path}:{_place(path.read_text(), anchor)}: "
    assert text.startswith(where + expected), text
