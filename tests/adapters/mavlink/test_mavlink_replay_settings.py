"""mavlink_replay's settings go through its pydantic ``Settings`` model: the YAML keys
(log, rate, segments) are as before, and each bad value is one error naming the
mission file's line and column and the key path."""

from __future__ import annotations

from pathlib import Path

import pytest
from plansys_bridge_adapters.mavlink.replay import MavlinkReplayPerformer, MavlinkReplaySettings

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission_config import load_mission

pytest.importorskip("pymavlink")

ROOT = Path(__file__).resolve().parents[3]
CONFIG = ROOT / "configs" / "flight_replay.yaml"


def _mission(tmp_path: Path, old: str = "", new: str = "") -> Path:
    text = CONFIG.read_text()
    text = text.replace("pddl/", str(ROOT / "configs" / "pddl") + "/")
    text = text.replace("../bags/logs/copter1.tlog", str(ROOT / "tests/data/logs/copter1.tlog"))
    assert old in text
    path = tmp_path / "flight.yaml"
    path.write_text(text.replace(old, new, 1))
    return path


def _line_col(path: Path, needle: str) -> str:
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if needle in line:
            return f"{path}:{number}:"
    raise AssertionError(needle)


def test_the_kind_declares_its_settings_model() -> None:
    assert MavlinkReplayPerformer.Settings is MavlinkReplaySettings
    assert not MavlinkReplayPerformer.settings_keys


def test_the_bundled_flight_loads(tmp_path: Path) -> None:
    (performer,) = load_mission(_mission(tmp_path)).performers
    assert performer.kind == "mavlink_replay"


@pytest.mark.parametrize(
    ("old", "new", "needle", "key", "says"),
    [
        ("rate: 1.0", 'rate: "2"', "rate:", "performers[0].rate", "number"),
        ("rate: 1.0", "rate: 0", "rate:", "performers[0].rate", "greater than 0"),
        (
            "{action: (fly copter1 pad field), start: 10, end: 40}",
            "{action: (fly copter1 pad field), start: 40, end: 10}",
            "start: 40, end: 10",
            "performers[0].segments[1]",
            "end 10 is not after start 40",
        ),
        (
            "{action: (takeoff copter1 pad), start: 0",
            "{action: takeoff, start: 0",
            "action: takeoff",
            "performers[0].segments[0].action",
            "an action such as (fly copter1 pad field), got 'takeoff'",
        ),
        ("    rate: 1.0", "    speed: 2\n    rate: 1.0", "speed:", "performers[0].speed", ""),
    ],
)
def test_a_bad_setting_names_file_line_and_key(
    tmp_path: Path, old: str, new: str, needle: str, key: str, says: str
) -> None:
    path = _mission(tmp_path, old, new)
    with pytest.raises(ConfigError) as info:
        load_mission(path)
    text = str(info.value)
    assert _line_col(path, needle) in text, text
    assert f"{key}: " in text, text
    assert says.lower() in text.lower(), text
