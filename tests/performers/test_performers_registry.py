"""Performer kinds come from the plansys_bridge.performers entry points."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError, PluginError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.performers import registry
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer


@pytest.fixture(autouse=True)
def _fresh_cache() -> Iterator[None]:
    registry.PERFORMERS.cache_clear()
    yield
    registry.PERFORMERS.cache_clear()


def _fake_entry_points(monkeypatch: pytest.MonkeyPatch, **points: str) -> None:
    eps = {
        name: EntryPoint(name=name, value=value, group=registry.ENTRY_POINT_GROUP)
        for name, value in points.items()
    }
    monkeypatch.setattr(registry.PERFORMERS, "entry_points", lambda: eps)
    monkeypatch.setattr(registry.PERFORMERS, "builtin", {})


def test_simulated_kind_is_installed() -> None:
    assert registry.load_performer_kind("simulated") is SimulatedPerformer
    assert "simulated" in registry.available_performer_kinds()


def test_unknown_kind_lists_the_known_ones() -> None:
    with pytest.raises(
        PluginError, match=r"unknown performer kind 'simulatd' \(known: .*simulated"
    ):
        registry.load_performer_kind("simulatd")


def test_missing_optional_dependency_names_the_extra(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    (tmp_path / "needs_mavlink_xyz.py").write_text("import pymavlink\nclass P: pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(sys.modules, "pymavlink", None)  # as if not installed
    _fake_entry_points(monkeypatch, drone="needs_mavlink_xyz:P")
    with pytest.raises(
        PluginError, match=r"needs the optional dependency 'pymavlink'.*plansys-bridge\[mavlink\]"
    ):
        registry.load_performer_kind("drone")
    sys.modules.pop("needs_mavlink_xyz", None)


def test_wrong_target_and_non_performer_class(monkeypatch: pytest.MonkeyPatch) -> None:
    _fake_entry_points(
        monkeypatch,
        gone="plansys_bridge.performers.no_such_module:X",
        typo="plansys_bridge.performers.simulated:SimulatedPerformr",
        notperf="plansys_bridge.hub.hub:Hub",
    )
    with pytest.raises(
        PluginError, match=r"no module named 'plansys_bridge\.performers\.no_such_module'"
    ):
        registry.load_performer_kind("gone")
    with pytest.raises(PluginError, match="could not be loaded"):
        registry.load_performer_kind("typo")
    with pytest.raises(PluginError, match="not an ActionPerformer subclass"):
        registry.load_performer_kind("notperf")


def test_missing_module_of_an_installed_package_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """``pkg.missing_module:X`` with pkg installed: the module is missing, not the package."""
    _fake_entry_points(monkeypatch, third="yaml.no_such_adapter:Performer")
    with pytest.raises(PluginError) as err:
        registry.load_performer_kind("third")
    assert "no module named 'yaml.no_such_adapter'" in str(err.value)
    assert "install the package" not in str(err.value)


def test_performers_from_config_names_the_entry(virtual_hub: Hub) -> None:
    ctx = PerformerContext(virtual_hub, virtual_hub.clock)
    entries = [
        {"kind": "simulated", "name": "r1", "actions": {"move": ["r1"]}},
        {"kind": "simulated", "name": "r2", "actions": {"move": ["r2"]}},
    ]
    built = registry.performers_from_config(entries, ctx)
    assert [p.node_name for p in built] == ["r1", "r2"]
    with pytest.raises(ConfigError) as err:
        registry.performers_from_config(
            [*entries, {"kind": "warp", "name": "x", "actions": ["go"]}], ctx
        )
    assert err.value.key == "performers[2].kind"
    with pytest.raises(ConfigError) as err:
        registry.performers_from_config(
            [*entries, {"kind": "simulated", "name": "r1", "actions": ["go"]}], ctx
        )
    assert err.value.key == "performers[2].name"
    with pytest.raises(ConfigError) as err:
        registry.performers_from_config([{"name": "r1", "actions": ["go"]}], ctx)
    assert err.value.key == "performers[0].kind"
