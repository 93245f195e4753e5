"""The rosbag entry's inline ``segments`` list is part of its settings model, so a bad
segment is an error when the mission loads, naming the file, line, column and key
path; a segments file is still read when the performer is built, and its errors
name the segments file's own line and column."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from plansys_bridge_adapters.rosbag.performer import BagNavigationPerformer
from plansys_bridge_adapters.rosbag.route import Route
from rosbag_testdata import DEMO_BAGS, REPO

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.mission_config import load_mission
from plansys_bridge.performers.base import PerformerContext

DOMAIN = REPO / "pddl" / "flat_navigation.pddl"

MISSION = """\
name: rosbag_segments_check
domain: {domain}
knowledge:
  instances: {{tiago: robot, kitchen: room, livingroom: room}}
  predicates: ["(robot_at tiago kitchen)", "(connected kitchen livingroom)"]
  functions: ["(= (travel_time kitchen livingroom) 12)"]
goal: (robot_at tiago livingroom)
performers:
  - kind: rosbag
    name: tiago_nav
    actions: {{move: [tiago]}}
    bag: kitchen_nav
    topic: /odom
    segments:
{first}
{second}
clock:
  kind: virtual
"""


FIRST = "      - {name: first, arguments: ['', kitchen, livingroom], start: 1.5, end: 13.5}"


def write_mission(folder: Path, second: str, *replace: tuple[str, str]) -> Path:
    """The mission with ``second`` as the second segment, then ``(old, new)`` edits."""
    text = MISSION.format(domain=DOMAIN, first=FIRST, second=second)
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    path = folder / "mission.yaml"
    path.write_text(text)
    return path


def written_at(path: Path, error: ConfigError) -> str:
    """The line of ``path`` the error names."""
    assert error.file == str(path) and error.line is not None, str(error)
    return path.read_text().splitlines()[error.line - 1]


def test_good_inline_list_loads_and_builds(virtual_hub: Hub, tmp_path: Path) -> None:
    """Items take the entry's bag and topic; the route serves the move it names."""
    for name in ("kitchen_nav", "kitchen_nav_ros1.bag"):
        target = tmp_path / name
        copy = shutil.copytree if (DEMO_BAGS / name).is_dir() else shutil.copy
        copy(DEMO_BAGS / name, target)
    path = write_mission(
        tmp_path, "      - {arguments: ['', livingroom, kitchen], bag: kitchen_nav_ros1.bag}"
    )
    mission = load_mission(path)
    [entry] = mission.performers
    assert entry.kind == "rosbag"
    context = PerformerContext(hub=virtual_hub, clock=virtual_hub.clock, base_dir=tmp_path)
    [performer] = BagNavigationPerformer.from_config(
        entry.model_dump(), context, key="performers[0]"
    )
    assert isinstance(performer, BagNavigationPerformer)
    first, second = performer.route.segments
    assert (first.bag, first.topic, first.start, first.end) == (
        (tmp_path / "kitchen_nav").resolve(),
        "/odom",
        1.5,
        13.5,
    )
    assert (second.bag, second.topic) == ((tmp_path / "kitchen_nav_ros1.bag").resolve(), "/odom")
    assert performer.route.select("move", ("tiago", "livingroom", "kitchen")) is second


@pytest.mark.parametrize(
    ("second", "key", "message"),
    [
        ("      - {start: 5, end: 2}", "segments[1].end", "end (2.0) must be after start (5.0)"),
        ("      - {start: -1}", "segments[1].start", "greater than or equal to 0, got -1"),
        ("      - {strat: 1}", "segments[1].strat", "unknown key (allowed: action, arguments"),
        ("      - {arguments: kitchen}", "segments[1].arguments", "valid list, got 'kitchen'"),
        ("      - {arguments: [kitchen, 3]}", "segments[1].arguments[1]", "valid string, got 3"),
        ("      - {end: soon}", "segments[1].end", "valid number, got 'soon'"),
        ("      - {end: .inf}", "segments[1].end", "finite number"),
        ("      - {action: ''}", "segments[1].action", "at least 1 character"),
        ("      - {bag: ''}", "segments[1].bag", "at least 1 character"),
        ("      - kitchen", "segments[1]", "a segment must be a mapping of arguments"),
    ],
)
def test_bad_inline_segment_is_a_load_error(
    tmp_path: Path, second: str, key: str, message: str
) -> None:
    path = write_mission(tmp_path, second)
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    text = str(err.value)
    assert err.value.key == f"performers[0].{key}", text
    assert written_at(path, err.value) == second, text
    assert f"{path}:{err.value.line}:{err.value.column}: performers[0].{key}: " in text
    assert message in text


@pytest.mark.parametrize("field", ["bag", "topic"])
def test_segment_without_bag_or_topic_anywhere(tmp_path: Path, field: str) -> None:
    """No default on the entry and none on the item: the item is where it is missing."""
    default = {"bag": "    bag: kitchen_nav\n", "topic": "    topic: /odom\n"}[field]
    path = write_mission(
        tmp_path,
        "      - {start: 20.0}",
        (default, ""),
        ("start: 1.5", "bag: kitchen_nav, topic: /odom, start: 1.5"),
    )
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert err.value.key == f"performers[0].segments[1].{field}", str(err.value)
    assert written_at(path, err.value) == "      - {start: 20.0}", str(err.value)
    assert f"give the segment's {field} or the performer's default {field}" in str(err.value)


def test_an_item_of_its_own_needs_no_default(tmp_path: Path) -> None:
    path = write_mission(
        tmp_path,
        "      - {bag: other, topic: /pose, start: 20.0}",
        ("    bag: kitchen_nav\n", ""),
        ("    topic: /odom\n", ""),
        ("start: 1.5", "bag: b, topic: /t, start: 1.5"),
    )
    assert load_mission(path).performers[0].kind == "rosbag"


def test_bad_default_is_reported_on_the_default(tmp_path: Path) -> None:
    """A wrong entry-level bag is its own error, not one per segment that uses it."""
    path = write_mission(tmp_path, "", ("bag: kitchen_nav", "bag: [kitchen_nav]"))
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert err.value.key == "performers[0].bag", str(err.value)


def test_segments_file_errors_name_the_file_line_and_key(virtual_hub: Hub, tmp_path: Path) -> None:
    """A file passes the load; building the performer reads it, and an error names
    the segments file's line and column and the item's key path."""
    segments = tmp_path / "moves.segments.yaml"
    segments.write_text(
        "- {arguments: ['', a, b], start: 1.0, end: 4.0}\n"
        "- arguments: ['', b, a]\n"
        "  start: 9.0\n"
        "  end: 3.0\n"
    )
    path = write_mission(
        tmp_path, "", (f"    segments:\n{FIRST}", "    segments: moves.segments.yaml")
    )
    mission = load_mission(path)
    context = PerformerContext(hub=virtual_hub, clock=virtual_hub.clock, base_dir=tmp_path)
    with pytest.raises(ConfigError) as err:
        BagNavigationPerformer.from_config(
            mission.performers[0].model_dump(), context, key="performers[0]"
        )
    assert err.value.key == "performers[0].segments[1].end", str(err.value)
    assert err.value.file == str(segments), str(err.value)
    assert (err.value.line, err.value.column) == (4, 3), str(err.value)
    assert "end (3.0) must be after start (9.0)" in str(err.value)


def test_route_from_a_list_keeps_the_caller_data(tmp_path: Path) -> None:
    """Filling in the defaults copies the items: the mission's data stays as written."""
    items = [{"arguments": ["a"], "start": 1.0}]
    route = Route.from_config(items, tmp_path, default_bag="b", default_topic="/t")
    assert items == [{"arguments": ["a"], "start": 1.0}]
    assert route.segments[0].bag == (tmp_path / "b").resolve()
    assert route.segments[0].topic == "/t"
