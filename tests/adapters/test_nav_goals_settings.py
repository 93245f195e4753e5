"""The navigation performers' location tables are part of their Settings models
(ros1_move_base and ros2_nav2 share nav_goals.NavGoalSettings), so a malformed table
is an error when the mission loads, naming the file, line, column and key path."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission_config import load_mission
from plansys_bridge.performers.entry import has_settings_model
from plansys_bridge.performers.registry import load_performer_kind

DOMAIN = Path(__file__).resolve().parents[2] / "configs" / "pddl" / "flat_navigation.pddl"

MISSION = """\
name: nav_locations_check
domain: {domain}
knowledge:
  instances: {{r1: robot, hall: room, kitchen: room}}
  predicates: ["(robot_at r1 hall)", "(connected hall kitchen)"]
goal: (visited r1 kitchen)
performers:
  - kind: {kind}
    name: r1_nav
    actions: {{move: [r1]}}
{connection}
{locations}
clock:
  kind: wall
"""

KINDS = {
    "ros1_move_base": "    master_uri: http://127.0.0.1:11311",
    "ros2_nav2": "    domain_id: 7",
}


def write_mission(tmp_path: Path, kind: str, kitchen: str, locations: str = "") -> Path:
    """The mission with ``kitchen`` as the table's second line, or ``locations`` as
    the whole ``locations:`` line."""
    table = locations or f"    locations:\n      hall: {{x: 0.0, y: 0.0}}\n{kitchen}"
    path = tmp_path / "mission.yaml"
    path.write_text(
        MISSION.format(domain=DOMAIN, kind=kind, connection=KINDS[kind], locations=table)
    )
    return path


def line_of(path: Path, text: str) -> int:
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if text in line:
            return number
    raise AssertionError(f"{text!r} not in {path}")


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_both_kinds_declare_a_settings_model_and_a_good_table_loads(
    tmp_path: Path, kind: str
) -> None:
    assert has_settings_model(load_performer_kind(kind))
    mission = load_mission(write_mission(tmp_path, kind, "      kitchen: {x: 4, y: 1, yaw: 1.57}"))
    assert [p.kind for p in mission.performers] == [kind]


@pytest.mark.parametrize("kind", sorted(KINDS))
@pytest.mark.parametrize(
    ("kitchen", "key", "message"),
    [
        ("      kitchen: {x: 4.0}", "locations.kitchen.y", "missing"),
        ("      kitchen: {x: 4.0, y: north}", "locations.kitchen.y", "valid number"),
        ("      kitchen: {x: 4.0, y: true}", "locations.kitchen.y", "valid number"),
        ("      kitchen: {x: 4.0, y: .nan}", "locations.kitchen.y", "finite number"),
        ("      kitchen: {x: 4.0, y: 1.0, z: 3}", "locations.kitchen.z", "unknown key"),
        ("      kitchen: [4.0, 1.0]", "locations.kitchen", "valid dictionary"),
        ("      Hall: {x: 4.0, y: 1.0}", "locations", "'hall' given twice"),
        ("      7: {x: 4.0, y: 1.0}", "locations", "names must be non-empty strings"),
    ],
)
def test_bad_table_is_a_load_error_with_its_place(
    tmp_path: Path, kind: str, kitchen: str, key: str, message: str
) -> None:
    path = write_mission(tmp_path, kind, kitchen)
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    text = str(err.value)
    line = line_of(path, kitchen.strip() if key != "locations" else "locations:")
    assert err.value.key == f"performers[0].{key}", text
    assert (err.value.file, err.value.line) == (str(path), line), text
    assert f"{path}:{line}:" in text and message in text, text


@pytest.mark.parametrize(
    ("kind", "value", "message"),
    [
        ("ros1_move_base", "places.yaml", "must map each destination"),
        ("ros2_nav2", "5", "or name a YAML file"),
        ("ros2_nav2", "{}", "at least 1 item"),
        ("ros2_nav2", "''", "must name a locations file"),
    ],
)
def test_bad_table_shape_names_the_locations_key(
    tmp_path: Path, kind: str, value: str, message: str
) -> None:
    path = write_mission(tmp_path, kind, "", locations=f"    locations: {value}")
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert err.value.key == "performers[0].locations", str(err.value)
    assert err.value.line == line_of(path, "locations:"), str(err.value)
    assert message in str(err.value)


def test_nav2_locations_file_errors_name_the_file_line_and_key(tmp_path: Path) -> None:
    """A locations file passes the load and is read when the performer is built."""
    from plansys_bridge_adapters.ros2_nav2.performer import Nav2Performer
    from plansys_bridge_adapters.ros2_nav2.settings import resolve

    places = tmp_path / "places.yaml"
    places.write_text("locations:\n  hall: {x: 0.0, y: 0.0}\n  kitchen: {x: 4.0}\n")
    path = write_mission(tmp_path, "ros2_nav2", "", locations="    locations: places.yaml")
    [entry] = load_mission(path).performers
    settings = Nav2Performer.parse_config(entry.model_dump(), key="performers[0]").settings
    with pytest.raises(ConfigError) as err:
        resolve(settings, "performers[0]", tmp_path)
    assert (err.value.file, err.value.line, err.value.key) == (
        str(places),
        3,
        "locations.kitchen.y",
    ), str(err.value)
    places.write_text("hall: {x: 0.0, y: 0.0}\nkitchen: {x: 4.0, y: 1.0, yaw: 1.57}\n")
    assert resolve(settings, "performers[0]", tmp_path).locations["kitchen"].yaw == 1.57
    bare = places.read_text() + "attic: {x: 1.0, y: [2]}\n"
    places.write_text(bare)
    with pytest.raises(ConfigError) as err:
        resolve(settings, "performers[0]", tmp_path)
    assert (err.value.line, err.value.key) == (3, "attic.y"), str(err.value)


def test_nav2_double_blocked_names_must_be_locations(tmp_path: Path) -> None:
    from plansys_bridge_adapters.ros2_nav2.settings import Nav2Settings, resolve

    settings = Nav2Settings.model_validate(
        {"locations": {"hall": {"x": 0.0, "y": 0.0}}, "double": {"blocked": ["hall", "moon"]}}
    )
    with pytest.raises(ConfigError) as err:
        resolve(settings, "performers[0]", tmp_path)
    assert err.value.key == "performers[0].double.blocked[1]"
    assert "'moon' is not a location" in str(err.value)


@pytest.mark.parametrize(
    ("line", "key", "message"),
    [
        ("    master_uri: ftp://127.0.0.1:11311", "master_uri", "must look like http://HOST:PORT"),
        ("    master_uri: http://127.0.0.1:port", "master_uri", "bad port"),
        ("    action_ns: /move base", "action_ns", "not a ROS topic name"),
    ],
)
def test_ros1_master_and_action_namespace_are_checked_when_the_mission_loads(
    tmp_path: Path, line: str, key: str, message: str
) -> None:
    path = tmp_path / "mission.yaml"
    path.write_text(
        MISSION.format(
            domain=DOMAIN,
            kind="ros1_move_base",
            connection=line,
            locations="    locations:\n      hall: {x: 0.0, y: 0.0}\n      kitchen: {x: 4, y: 1}",
        )
    )
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    text = str(err.value)
    assert err.value.key == f"performers[0].{key}", text
    assert f"{path}:{line_of(path, line.strip())}:" in text and message in text, text
