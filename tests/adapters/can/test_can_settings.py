"""The CAN entry's inline location table is part of its settings model, so a bad
table is an error when the mission loads, naming the file, line, column and key."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission_config import load_mission

DOMAIN = Path(__file__).resolve().parents[3] / "configs" / "can" / "mobile_base_domain.pddl"

MISSION = """\
name: can_locations_check
domain: {domain}
knowledge:
  instances: {{r2d2: robot, dock: location, hall: location}}
  predicates: ["(robot_at r2d2 dock)"]
goal: (robot_at r2d2 hall)
performers:
  - kind: can
    name: base_r2d2
    robot: r2d2
    actions:
      move: {{robot: 0, destination: 2}}
    bus: {{interface: virtual, channel: settings_can0}}
    simulate_base: {{x: 0.0, y: 0.0}}
    locations:
      dock: [0.0, 0.0]
{hall}
clock:
  kind: virtual
"""


def write_mission(tmp_path: Path, hall: str) -> Path:
    path = tmp_path / "mission.yaml"
    path.write_text(MISSION.format(domain=DOMAIN, hall=hall))
    return path


def line_of(path: Path, text: str) -> int:
    """1-based line of the first line of ``path`` holding ``text``."""
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if text in line:
            return number
    raise AssertionError(f"{text!r} not in {path}")


def test_good_inline_table_loads(tmp_path: Path) -> None:
    mission = load_mission(write_mission(tmp_path, "      hall: {x: 3.0, y: 0.0, yaw: 1.57}"))
    [entry] = mission.performers
    assert entry.kind == "can"


@pytest.mark.parametrize(
    ("hall", "key", "message"),
    [
        ("      hall: [3.0]", "locations.hall", "must be [x, y] or [x, y, yaw]"),
        ("      hall: [3.0, 1.0, 0.0, 2.0]", "locations.hall", "must be [x, y] or [x, y, yaw]"),
        ("      hall: [3.0, north]", "locations.hall.y", "valid number, got 'north'"),
        ("      hall: {x: 3.0, y: .nan}", "locations.hall.y", "finite number"),
        ("      hall: {x: 3.0}", "locations.hall.y", "missing"),
        ("      hall: {x: 3.0, y: 1.0, yaww: 0}", "locations.hall.yaww", "unknown key"),
        ("      hall: {x: 3, y: 1, via: [[1.0]]}", "locations.hall.via[0]", "at least 2"),
        ("      hall: {x: 3.0, y: true}", "locations.hall.y", "valid number, got True"),
    ],
)
def test_bad_inline_location_is_a_load_error(
    tmp_path: Path, hall: str, key: str, message: str
) -> None:
    path = write_mission(tmp_path, hall)
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    line = line_of(path, hall.strip())
    text = str(err.value)
    assert err.value.key == f"performers[0].{key}", text
    assert err.value.file == str(path), text
    assert err.value.line == line, text
    assert f"{path}:{line}:" in text
    assert message in text


@pytest.mark.parametrize(
    ("locations", "message"),
    [
        ("    locations: 5", "must be a locations file or a mapping"),
        ("    locations: {}", "at least 1 item"),
        ("    locations: ''", "must name a locations file"),
        ("    locations:\n      1: [0.0, 0.0]", "location names must be non-empty strings"),
    ],
)
def test_bad_table_shape_names_the_locations_key(
    tmp_path: Path, locations: str, message: str
) -> None:
    text = MISSION.format(domain=DOMAIN, hall="").replace(
        "    locations:\n      dock: [0.0, 0.0]\n", locations + "\n"
    )
    path = tmp_path / "mission.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert err.value.key == "performers[0].locations", str(err.value)
    assert err.value.line == line_of(path, "locations:"), str(err.value)
    assert message in str(err.value)


def test_locations_file_name_passes_the_load(tmp_path: Path) -> None:
    """A file name passes the model; the file is read when the performer is built."""
    text = MISSION.format(domain=DOMAIN, hall="").replace(
        "    locations:\n      dock: [0.0, 0.0]\n", "    locations: places.yaml\n"
    )
    path = tmp_path / "mission.yaml"
    path.write_text(text)
    mission = load_mission(path)
    assert mission.performers[0].model_dump()["locations"] == "places.yaml"
