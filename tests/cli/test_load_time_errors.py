"""Mistakes found when the mission loads (or right after planning), in one line.

Each case used to be a traceback or a long wait: an adapter whose ``setup()`` raises,
a misspelt MAVLink URL scheme, YAML nested hundreds deep, a NUL byte in a path, a
negative default altitude, a domain file that does not exist, an action no
performer offers.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml
from test_bad_input import error_line

from plansys_bridge.cli import main

ROOT = Path(__file__).resolve().parents[2]
CONFIGS = ROOT / "configs"


def copter(tmp_path: Path, **performer: Any) -> Path:
    """configs/mavlink_copter.yaml with absolute paths and ``performer`` keys changed."""
    data = yaml.safe_load((CONFIGS / "mavlink_copter.yaml").read_text())
    data["domain"] = str(CONFIGS / data["domain"])
    data["problem"] = str(CONFIGS / data["problem"])
    entry = data["performers"][0]
    entry["locations"] = str(CONFIGS / entry["locations"])
    entry.pop("double")
    entry["url"] = "tcp:127.0.0.1:9"
    entry["timeouts"]["connect"] = 1
    entry.update(performer)
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_setup_failure_is_one_line_naming_performer_and_cause(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Nothing listens on port 9: the MAVLink adapter's setup() raises."""
    assert main(["run", str(copter(tmp_path))]) == 2
    out = capsys.readouterr()
    assert "uav1_performer: connecting to MAVLink tcp:127.0.0.1:9" in out.out
    assert "Traceback" not in out.err
    [line] = out.err.strip().splitlines()
    assert line.startswith("error: performer 'uav1_performer' could not start: tcp:127.0.0.1:9")


def test_misspelt_url_scheme_is_found_at_load(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = copter(tmp_path, url="tpc:127.0.0.1:5760")
    assert main(["run", str(path)]) == 2
    line = error_line(capsys)
    [(row, text)] = [
        (n, t) for n, t in enumerate(path.read_text().splitlines(), 1) if "url: tpc:" in t
    ]
    col = text.index("url") + 1
    assert line.startswith(
        f"error: {path}:{row}:{col}: performers[0].url: tpc:127.0.0.1:5760: unknown"
    )
    assert "did you mean tcp:?" in line


def test_negative_default_alt_names_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    places = {"default_alt": -5, "locations": {"pad": {"north": 0, "east": 0}}}
    path = copter(tmp_path, locations=places)
    assert main(["run", str(path)]) == 2
    assert error_line(capsys).startswith(
        f"error: {path}:25:5: performers[0].locations.default_alt: must be > 0"
    )


def test_negative_default_alt_in_a_locations_file_names_its_place_and_the_mission_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    places = tmp_path / "places.yaml"
    places.write_text("locations:\n  pad: {north: 0, east: 0}\ndefault_alt: -5\n")
    path = copter(tmp_path, locations="places.yaml")
    assert main(["run", str(path)]) == 2
    assert error_line(capsys) == (
        f"error: {places}:3:1: default_alt: must be > 0 metres above home, got -5 "
        "(in the locations file of performers[0].locations)"
    )


def test_nul_byte_in_a_locations_path(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = copter(tmp_path, locations="places\0.yaml")
    assert main(["run", str(path)]) == 2
    assert error_line(capsys).startswith(f"error: {path}:24:3: performers[0].locations: a NUL byte")


def _cooking(tmp_path: Path, **changes: Any) -> Path:
    data = yaml.safe_load((CONFIGS / "demo_cooking.yaml").read_text())
    data["domain"] = str(CONFIGS / data["domain"])
    data["clock"] = {"kind": "virtual"}
    data.update(changes)
    path = tmp_path / "cooking.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_nul_byte_in_the_domain_path(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _cooking(tmp_path, domain="a\0b.pddl")
    assert main(["run", str(path)]) == 2
    assert error_line(capsys).startswith(f"error: {path}:3:1: domain: a NUL byte in 'a\\x00b.pddl'")


def test_missing_domain_names_the_mission_file_and_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _cooking(tmp_path, domain="nan")
    assert main(["run", str(path)]) == 2
    line = error_line(capsys)
    assert line.startswith(
        f"error: {path}:3:1: domain: {tmp_path / 'nan'}: cannot read domain file"
    )


@pytest.mark.parametrize(("value", "shown"), [(math.nan, "nan"), (3, "3"), (True, "True")])
def test_a_domain_that_is_not_a_path_names_the_mission_file_and_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], value: Any, shown: str
) -> None:
    path = _cooking(tmp_path, domain=value)
    assert main(["run", str(path)]) == 2
    assert error_line(capsys) == (
        f"error: {path}:3:1: domain: a domain file path or a list of them, got {shown}"
    )


@pytest.mark.parametrize("depth", [101, 400, 5000])
def test_deeply_nested_yaml_names_file_and_place(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], depth: int
) -> None:
    path = tmp_path / "deep.yaml"
    path.write_text(
        "name: x\nperformers:\n  - {kind: simulated, tags: " + "[" * depth + "]" * depth + "}\n"
    )
    assert main(["run", str(path)]) == 2
    line = error_line(capsys)
    assert re.match(rf"error: {re.escape(str(path))}:3:\d+: performers\[0\]\.tags\[0\]", line)
    assert "nested more than 100 levels deep" in line


def test_nesting_within_the_limit_is_plain_yaml(tmp_path: Path) -> None:
    from plansys_bridge.mission_config import load_yaml_file

    path = tmp_path / "ok.yaml"
    path.write_text("a: " + "[" * 99 + "]" * 99 + "\n")
    value = load_yaml_file(path)["a"]
    depth = 0
    while value:
        value, depth = value[0], depth + 1
    assert depth == 98  # 99 lists, the innermost empty


def test_action_no_performer_offers_is_reported_after_planning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """robot1's base is missing: its moves are reported at once, not after replans."""
    data = yaml.safe_load((CONFIGS / "demo_cooking.yaml").read_text())
    performers = [p for p in data["performers"] if p["name"] != "robot1_base"]
    path = _cooking(tmp_path, performers=performers, events=[])
    assert main(["run", str(path), "--json"]) == 1
    out = capsys.readouterr().out
    assert '"status": "no performer"' in out
    assert "no performer offers (move robot1" in out
