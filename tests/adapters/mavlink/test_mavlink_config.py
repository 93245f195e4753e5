"""Mission-file entries of kind mavlink: every mistake names its key."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
import yaml
from mavlink_support import CONFIGS, build, make_hub, performer_config
from plansys_bridge_adapters.mavlink.performer import MavlinkPerformer
from plansys_bridge_adapters.mavlink.settings import default_command

from plansys_bridge.clock import VirtualClock
from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.mission_config import load_mission
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.registry import load_performer_kind

URL = "tcp:127.0.0.1:5760"


def entry(**changes: Any) -> dict[str, Any]:
    config = performer_config("uav1", URL, "copter")
    for k, v in changes.items():
        if v is None:
            config.pop(k, None)
        else:
            config[k] = v
    return config


def test_entry_point_finds_the_performer() -> None:
    assert load_performer_kind("mavlink") is MavlinkPerformer


def test_vehicle_argument_is_specialised() -> None:
    performer = build(entry(), make_hub())
    assert performer.actions["fly"] == ("uav1",)
    assert performer.actions["hold"] == ("uav1",)
    assert performer.commands["fly"].target_arg == 2
    assert performer.settings.vehicle == "uav1"


def test_actions_without_commands_do_what_their_name_says() -> None:
    performer = build(
        entry(
            commands=None,
            actions={"takeoff": ["uav1"], "goto_wp": ["uav1"], "return_to_launch": []},
        ),
        make_hub(),
    )
    assert performer.commands["takeoff"].do == "takeoff"
    assert performer.commands["goto_wp"].do == "goto"
    assert performer.commands["goto_wp"].target_arg == -1
    assert performer.commands["return_to_launch"].do == "rtl"
    assert default_command("LAND").do == "land"


@pytest.mark.parametrize(
    ("changes", "key", "message"),
    [
        ({"url": None}, "performers[0].url", "exactly one of url"),
        ({"double": {"model": "copter"}}, "performers[0].url", "exactly one of url"),
        ({"url": 5760}, "performers[0].url", "valid string, got 5760"),
        ({"colour": "red"}, "performers[0].colour", "unknown key"),
        ({"model": "plane"}, "performers[0].model", "'copter' or 'rover', got 'plane'"),
        (
            {"commands": {"fly": {"do": "teleport"}}},
            "performers[0].commands.fly.do",
            "'hold', got 'teleport'",
        ),
        (
            {"commands": {"fly": {"do": "goto", "target": 2}}},
            "performers[0].commands.fly.target",
            "unknown key",
        ),
        (
            {"commands": {"fly": {"do": "goto", "vehicle_arg": -1}}},
            "performers[0].commands.fly.vehicle_arg",
            "greater than or equal to 0, got -1",
        ),
        ({"commands": {"swim": "goto"}}, "performers[0].commands", "not listed in actions"),
        (
            {"actions": {"fly": ["uav2"]}, "commands": {"fly": {"do": "goto", "vehicle_arg": 0}}},
            "performers[0].commands.fly.vehicle_arg",
            "specialises it to 'uav2'",
        ),
        ({"timeouts": {"ekf": 0}}, "performers[0].timeouts.ekf", "greater than 0, got 0"),
        ({"timeouts": {"boot": 3}}, "performers[0].timeouts.boot", "unknown key"),
        ({"telemetry": {"battery": "b"}}, "performers[0].telemetry.battery", "unknown key"),
        (
            {"telemetry": {"low_battery_threshold": -1}},
            "performers[0].telemetry.low_battery_threshold",
            "greater than or equal to 0, got -1",
        ),
        (
            {"locations": {"locations": {"a": {"north": "far"}}}},
            "performers[0].locations.locations.a.north",
            "must be a number",
        ),
        (
            {"url": None, "double": {"model": "copter", "speed": 3}},
            "performers[0].double.speed",
            "unknown key",
        ),
        (
            {"url": None, "double": {"model": "copter", "speedup": -3}},
            "performers[0].double.speedup",
            "greater than 0, got -3",
        ),
        ({"cruise_altitude": "high"}, "performers[0].cruise_altitude", "valid number, got .high."),
    ],
)
def test_config_errors_name_the_key(changes: dict[str, Any], key: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as info:
        build(entry(**changes), make_hub())
    assert info.value.key == key


def test_virtual_clock_is_refused() -> None:
    hub = Hub(InProcessTransport(), VirtualClock())
    context = PerformerContext(hub=hub, clock=hub.clock, base_dir=CONFIGS)
    with pytest.raises(ConfigError, match="runs in real time") as info:
        MavlinkPerformer.from_config(entry(), context, key="performers[0]")
    assert info.value.key == "clock.kind"


@pytest.mark.parametrize(
    "name", ["mavlink_copter.yaml", "mavlink_rover.yaml", "mavlink_fleet.yaml"]
)
def test_shipped_missions_build_their_performers(name: str) -> None:
    mission = load_mission(CONFIGS / name)
    raw = yaml.safe_load((CONFIGS / name).read_text())
    assert all("double" in p for p in raw["performers"])  # runs anywhere by default

    async def main() -> list[MavlinkPerformer]:
        hub = make_hub()
        context = PerformerContext(hub=hub, clock=hub.clock, base_dir=mission.base_dir)
        built: list[MavlinkPerformer] = []
        for i, p in enumerate(mission.performers):
            [performer] = MavlinkPerformer.from_config(
                p.model_dump(), context, key=f"performers[{i}]"
            )
            assert isinstance(performer, MavlinkPerformer)
            built.append(performer)
        return built

    performers = asyncio.run(main())
    for performer in performers:
        vehicle = performer.settings.vehicle
        assert all(spec and spec[0] == vehicle for spec in performer.actions.values())
        assert performer.settings.locations is not None
        assert "pad" in performer.settings.locations
