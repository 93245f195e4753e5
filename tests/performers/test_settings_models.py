"""The simulated, bt and rosbag performers declare their settings as pydantic models,
so the mission loader checks their keys before anything is built: an error names the
file, line, column and key path."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission_config import load_mission
from plansys_bridge.performers.entry import has_settings_model
from plansys_bridge.performers.registry import load_performer_kind

DOMAIN = Path(__file__).resolve().parents[1] / "data" / "bt_example.pddl"

MISSION = """\
name: settings_models
domain: {domain}
knowledge:
  instances: {{r2d2: robot, wheels_zone: zone, assembly_zone: zone}}
  predicates: ["(robot_at r2d2 assembly_zone)"]
goal: (robot_at r2d2 wheels_zone)
performers:
  - kind: simulated
    name: sim
    actions: {{move: [r2d2]}}
    durations: {{move: 2.0}}
    faults: {{die_rate: 0.0}}
  - kind: bt
    name: tree
    actions: {{move: [r2d2]}}
    trees: {{move: bt/move.xml}}
    tick_period: 0.5
  - kind: rosbag
    name: bag
    actions: {{move: [r2d2]}}
    bag: kitchen_nav
    segments: kitchen_nav.segments.yaml
    knowledge:
      functions: {{x: robot_x}}
clock: {{kind: virtual}}
"""


@pytest.mark.parametrize("kind", ["simulated", "bt", "rosbag"])
def test_kind_declares_a_settings_model(kind: str) -> None:
    cls = load_performer_kind(kind)
    assert has_settings_model(cls)
    assert not cls.settings_keys


def test_the_mission_loads(tmp_path: Path) -> None:
    path = tmp_path / "mission.yaml"
    path.write_text(MISSION.format(domain=DOMAIN))
    assert [p.kind for p in load_mission(path).performers] == ["simulated", "bt", "rosbag"]


@pytest.mark.parametrize(
    ("old", "new", "key", "message"),
    [
        (
            "durations: {move: 2.0}",
            "durations: {move: -2}",
            "[0].durations.move",
            "greater than or equal to 0",
        ),
        ("durations: {move: 2.0}", "durations: {mvoe: 2}", "[0].durations.mvoe", "not one of"),
        (
            "faults: {die_rate: 0.0}",
            "faults: {die_rate: 2}",
            "[0].faults.die_rate",
            "less than or equal to 1",
        ),
        ("faults: {die_rate: 0.0}", "fautls: {die_rate: 0}", "[0].fautls", "unknown key"),
        ("tick_period: 0.5", "tick_period: fast", "[1].tick_period", "valid number"),
        ("trees: {move: bt/move.xml}", "trees: {fly: f.xml}", "[1].trees.fly", "not one of"),
        ("trees: {move: bt/move.xml}", "trees: {move: 3}", "[1].trees.move", "valid string"),
        ("bag: kitchen_nav", "bag: [kitchen_nav]", "[2].bag", "valid string"),
        ("segments: kitchen_nav.segments.yaml", "segments: []", "[2].segments", "non-empty"),
        (
            "segments: kitchen_nav.segments.yaml",
            "segments: [{topic: /odom, start: 5, end: 1}]",
            "[2].segments[0].end",
            "must be after start",
        ),
        ("functions: {x: robot_x}", "functions: {w: robot_w}", "[2].knowledge.functions", "'w'"),
        ("functions: {x: robot_x}", "robot_argument: -1", "[2].knowledge.robot_argument", "0"),
        ("functions: {x: robot_x}", "period: 2", "[2].knowledge.functions", "missing"),
    ],
)
def test_bad_setting_names_file_line_and_key(
    tmp_path: Path, old: str, new: str, key: str, message: str
) -> None:
    text = MISSION.format(domain=DOMAIN)
    assert old in text
    path = tmp_path / "mission.yaml"
    path.write_text(text.replace(old, new))
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    error = err.value
    assert error.key == f"performers{key}", str(error)
    assert error.file == str(path) and error.line is not None, str(error)
    written = path.read_text().splitlines()[error.line - 1]
    # the key's line, or its mapping's line when the key is missing
    parts = [part for part in re.split(r"[.\[\]]", key) if part and not part.isdigit()]
    assert any(part in written for part in parts), (str(error), written)
    assert f"{path}:{error.line}:{error.column}: performers{key}: " in str(error)
    assert message in str(error)
