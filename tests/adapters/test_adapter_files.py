"""Files an adapter reads (locations, segments) fail like every other user file:
one ConfigError naming the file and the mission key, never a decoding traceback."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from plansys_bridge_adapters.can.settings import load_locations as can_locations
from plansys_bridge_adapters.mavlink.locations import load_locations as mavlink_locations
from plansys_bridge_adapters.rosbag.route import _load_segments_file

from plansys_bridge.errors import ConfigError

LOADERS: dict[str, Callable[[Path], Any]] = {
    "can": lambda p: can_locations(str(p), p.parent, "performers[0].locations"),
    "mavlink": lambda p: mavlink_locations(str(p), p.parent, "performers[0].locations"),
    "rosbag": lambda p: _load_segments_file(p, "performers[0].segments"),
}


@pytest.mark.parametrize("adapter", sorted(LOADERS))
def test_binary_file_names_file_and_position(adapter: str, tmp_path: Path) -> None:
    f = tmp_path / "places.yaml"
    f.write_bytes(b"kitchen:\n  x: 1\n\x89PNG\x00\xff")
    with pytest.raises(ConfigError) as info:
        LOADERS[adapter](f)
    text = str(info.value)
    assert f"{f}:3:1" in text
    assert "not UTF-8" in text


@pytest.mark.parametrize("adapter", sorted(LOADERS))
def test_yaml_error_is_one_line_with_line_and_column(adapter: str, tmp_path: Path) -> None:
    f = tmp_path / "places.yaml"
    f.write_text("locations:\n  kitchen: {x: 1\n  hall: 2\n")
    with pytest.raises(ConfigError) as info:
        LOADERS[adapter](f)
    text = str(info.value)
    assert text.startswith(f"{f}:")
    assert "not valid YAML" in text
    assert "\n" not in text


@pytest.mark.parametrize("adapter", sorted(LOADERS))
def test_missing_file_names_the_key(adapter: str, tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as info:
        LOADERS[adapter](tmp_path / "nope.yaml")
    assert info.value.key is not None and info.value.key.startswith("performers[0].")
    assert "nope.yaml" in str(info.value)
