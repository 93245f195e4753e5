"""Mission files are validated whole on load; every error names file and key."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission import build_knowledge
from plansys_bridge.mission_config import load_mission, mission_from_dict
from plansys_bridge.pddl.parser import parse_domain_files

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

BASE = {
    "domain": "pddl/cooking_domain.pddl",
    "goal": "(and (battery_full r1))",
    "knowledge": {"instances": {"r1": "robot"}},
    "performers": [{"kind": "simulated", "name": "r1", "actions": {"recharge": ["r1"]}}],
}


def _error(data: object) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        mission_from_dict(data, source="m.yaml", base_dir=CONFIGS)
    return info.value


@pytest.mark.parametrize(
    ("change", "key", "words"),
    [
        ({"clokc": {}}, "clokc", "unknown key"),
        ({"clock": {"kind": "sundial"}}, "clock.kind", "'wall' or 'virtual'"),
        ({"clock": {"time_scale": 0}}, "clock.time_scale", "greater than 0"),
        ({"performers": [{"kind": "simulated"}]}, "performers[0].name", "required"),
        ({"performers": []}, "performers", "at least 1"),
        (
            {"replanning": {"max_replans": -1}},
            "replanning.max_replans",
            "must be >= 0",
        ),
        ({"auction": {"selection": "cheapest"}}, "auction.selection", "cheapest"),
        ({"execution": {"at_start_timout": 3}}, "execution.at_start_timout", "unknown setting"),
        ({"auction": {"retry_period": -1}}, "auction.retry_period", "-1"),
        ({"events": [{"at": 3}]}, "events[0]", "exactly one"),
        ({"goal": None}, None, "problem file or a goal"),
    ],
)
def test_config_errors_name_the_key(change: dict[str, object], key: str | None, words: str) -> None:
    err = _error(BASE | change)
    assert err.key == key
    assert words in str(err)
    assert str(err).startswith("m.yaml")


def test_duplicate_performer_names_are_refused() -> None:
    p = BASE["performers"][0]  # type: ignore[index]
    err = _error(BASE | {"performers": [p, p]})
    assert "repeated: r1" in str(err)


def test_yaml_syntax_error_names_line_and_column(tmp_path: Path) -> None:
    f = tmp_path / "bad.yaml"
    f.write_text("domain: [a.pddl\ngoal: x\n")
    with pytest.raises(ConfigError) as info:
        load_mission(f)
    assert f"{f}:" in str(info.value)
    assert "not valid YAML" in str(info.value)


def test_missing_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read mission file"):
        load_mission(tmp_path / "nope.yaml")


def test_paths_resolve_against_the_file() -> None:
    mission = load_mission(CONFIGS / "demo_cooking.yaml")
    assert mission.domain_paths == [CONFIGS / "pddl" / "cooking_domain.pddl"]


def test_bad_knowledge_entry_names_its_key_and_loads_nothing() -> None:
    mission = mission_from_dict(
        BASE
        | {
            "knowledge": {
                "instances": {"r1": "robot", "kitchen": "zone"},
                "predicates": ["(robot_at r1 kitchen)", "(robot_at r1 nowhere)"],
            }
        },
        source="m.yaml",
        base_dir=CONFIGS,
    )
    domain = parse_domain_files(mission.domain_paths)
    with pytest.raises(ConfigError) as info:
        build_knowledge(mission, domain)
    assert info.value.key == "knowledge.predicates[1]"
    assert "nowhere" in str(info.value)


def test_every_shipped_mission_config_validates() -> None:
    shipped = sorted(CONFIGS.glob("*.yaml"))
    missions = [p for p in shipped if "performers:" in p.read_text()]
    assert missions, "configs/ holds mission files"
    for path in missions:
        mission = load_mission(path)
        for domain in mission.domain_paths:
            assert domain.exists(), f"{path}: domain {domain} missing"
