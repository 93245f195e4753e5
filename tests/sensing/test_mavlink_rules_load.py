"""MAVLink rules are checked against pymavlink's ArduPilot dialect when the mission
loads: message names, field names (arrays by index, HEARTBEAT's mode) and values."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission import build_knowledge, load_domain
from plansys_bridge.mission_config import load_mission

pytest.importorskip("pymavlink")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

MISSION = """
name: copter_sensing
domain: {configs}/pddl/drone_domain.pddl
problem: {configs}/pddl/drone_problem_copter.pddl
performers:
  - kind: mavlink
    name: uav1_performer
    vehicle: uav1
    url: tcp:127.0.0.1:5760
    locations: {configs}/mavlink_locations.yaml
    actions: {{takeoff: [], fly: [], land: []}}
sensing:
  - from: mavlink
    performer: uav1_performer
    message: {message}
    when: {when}
    predicate: (battery_low uav1)
  - from: mavlink
    performer: uav1_performer
    message: SYS_STATUS
    field: {field}
    function: (battery uav1)
clock: {{kind: wall}}
"""

GOOD = {
    "message": "BATTERY_STATUS",
    "when": "battery_remaining < 25 and voltages[0] > 0",
    "field": "voltage_battery / 1000",
}


def _load(tmp_path: Path, **changes: str) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(MISSION.format(configs=CONFIGS, **(GOOD | changes)))
    mission = load_mission(path)
    build_knowledge(mission, load_domain(mission))


def test_good_rules_load(tmp_path: Path) -> None:
    _load(tmp_path)
    _load(tmp_path, message="HEARTBEAT", when="mode == 'RTL' or base_mode % 2 == 1")


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            {"message": "BATTERY_STATU"},
            ":15:14: sensing[0].message: no MAVLink message 'BATTERY_STATU' in the ArduPilot "
            "dialect (did you mean BATTERY_STATUS?)",
        ),
        (
            {"when": "battery_remainig < 25"},
            ":16:11: sensing[0].when: no field 'battery_remainig' in what this rule reads "
            "(did you mean 'battery_remaining'?)",
        ),
        ({"when": "voltages[10] > 0"}, ":16:11: sensing[0].when: no field 'voltages[10]'"),
        ({"when": "custom_mode == 4"}, ":16:11: sensing[0].when: no field 'custom_mode'"),
        ({"field": "voltage_batt / 1000"}, ":21:12: sensing[1].field: SYS_STATUS has no field"),
        ({"field": "voltage_battery /"}, ":21:12: sensing[1].field: column 18: unexpected"),
    ],
)
def test_unknown_messages_and_fields_name_file_line_column_and_key(
    tmp_path: Path, change: dict[str, str], expected: str
) -> None:
    with pytest.raises(ConfigError) as info:
        _load(tmp_path, **change)
    assert str(info.value).startswith(f"{tmp_path / 'm.yaml'}{expected}"), info.value


def test_a_rule_on_a_performer_of_another_kind_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    text = MISSION.format(configs=CONFIGS, **GOOD).replace("from: mavlink", "from: can", 1)
    path.write_text(text)
    mission = load_mission(path)
    with pytest.raises(
        ConfigError,
        match=r"sensing\[0\]\.performer: performer 'uav1_performer' "
        r"is of kind 'mavlink'; a can rule reads a can performer",
    ):
        build_knowledge(mission, load_domain(mission))
