"""One plugin shape for performers, solvers, transports and sensing sources.

Third-party plugins here are real installed distributions: a package and its
``.dist-info`` (with ``entry_points.txt``) written to a folder on ``sys.path``, found
by :mod:`importlib.metadata` exactly as ``pip install`` would leave them.
"""

from __future__ import annotations

import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pydantic import Field

from plansys_bridge import plugins
from plansys_bridge.errors import ConfigError, PluginError
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.hub.transport_kinds import TRANSPORTS, DdsKind, TransportContext
from plansys_bridge.mission_config import load_mission
from plansys_bridge.performers.registry import PERFORMERS
from plansys_bridge.planning.solvers import SOLVERS
from plansys_bridge.plugins import GROUPS, PluginSettings, validate_settings
from plansys_bridge.sensing.source import SENSING_SOURCES, SensingSource

ROOT = Path(__file__).resolve().parents[1]
DOMAIN = ROOT / "configs" / "pddl" / "flat_navigation.pddl"


@pytest.fixture
def installed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    """``install(dist, {module: source}, {group: {name: target}})``: a distribution
    importlib.metadata finds, removed again after the test."""
    site = tmp_path / "site"
    site.mkdir()
    monkeypatch.syspath_prepend(str(site))
    modules: list[str] = []

    def install(dist: str, sources: dict[str, str], points: dict[str, dict[str, str]]) -> None:
        for module, text in sources.items():
            (site / f"{module}.py").write_text(text)
            modules.append(module)
        info = site / f"{dist}-0.1.dist-info"
        info.mkdir()
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n")
        lines = []
        for group, entries in points.items():
            lines.append(f"[{group}]")
            lines += [f"{name} = {target}" for name, target in entries.items()]
        (info / "entry_points.txt").write_text("\n".join(lines) + "\n")
        _forget()

    yield install
    for module in modules:
        sys.modules.pop(module, None)
    monkeypatch.undo()
    _forget()


def _forget() -> None:
    plugins._entry_points.cache_clear()
    for registry in (PERFORMERS, SOLVERS, TRANSPORTS, SENSING_SOURCES):
        registry.cache_clear()


def test_builtins_register_through_the_entry_points() -> None:
    """Each registry's built-in list is exactly what pyproject.toml registers."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"]
    for kind, registry in (
        ("performers", PERFORMERS),
        ("solvers", SOLVERS),
        ("transports", TRANSPORTS),
        ("sensing_sources", SENSING_SOURCES),
    ):
        assert project[GROUPS[kind]] == registry.builtin, kind
        installed = {name: ep.value for name, ep in registry.entry_points().items()}
        for name, target in registry.builtin.items():
            assert installed.get(name) == target, f"{kind} {name}: reinstall the package"


def test_every_builtin_has_the_shape() -> None:
    """A base class per kind and, on every built-in, a strict pydantic Settings model."""
    pytest.importorskip("pymavlink", reason="the mavlink sensing source needs pymavlink")
    pytest.importorskip("cantools", reason="the can sensing source needs cantools")
    for registry in (SOLVERS, TRANSPORTS, SENSING_SOURCES):
        for name in registry.builtin:
            cls = registry.load(name)
            assert issubclass(cls, registry.base)
            model = plugins.settings_model(cls)
            assert model is not None and issubclass(model, PluginSettings), name


def test_settings_errors_name_the_key_path() -> None:
    class Inner(PluginSettings):
        rate: float = Field(1.0, gt=0)

    class Outer(PluginSettings):
        name: str
        inner: Inner = Field(default_factory=Inner)
        items: list[Inner] = Field(default_factory=list)

    assert validate_settings(Outer, {"name": "a", "inner": {"rate": 2}}).inner.rate == 2.0
    cases: list[tuple[dict[str, Any], str, str]] = [
        ({"name": "a", "inner": {"rate": -1}}, "p[0].inner.rate", "greater than 0, got -1"),
        ({"name": "a", "inner": {"rte": 1}}, "p[0].inner.rte", "unknown key (allowed: rate)"),
        ({"name": "a", "items": [{}, {"rate": "5"}]}, "p[0].items[1].rate", "got '5'"),
        ({"name": "a", "inner": {"rate": float("nan")}}, "p[0].inner.rate", "finite"),
        ({"name": True}, "p[0].name", "valid string"),
        ({}, "p[0].name", "required"),
        ({"name": "a", "x": 1}, "p[0].x", "allowed: inner, items, kind, name"),
    ]
    for data, key, words in cases:
        with pytest.raises(ConfigError) as err:
            validate_settings(Outer, data, key="p[0]", known=("kind",))
        assert err.value.key == key, str(err.value)
        assert words in str(err.value)


THIRD_PARTY = '''
import asyncio
from typing import Any, ClassVar

from pydantic import Field

from plansys_bridge.performers.base import ActionGoal, ActionPerformer
from plansys_bridge.plugins import PluginSettings


class Gripper(ActionPerformer):
    class Settings(PluginSettings):
        force: float = Field(10.0, gt=0)

    def __init__(self, *args: Any, settings: "Gripper.Settings", **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.force = settings.force

    async def execute(self, goal: ActionGoal) -> str:
        await self.clock.sleep(1.0)
        self.feedback(1.0)
        return f"held with {self.force}"


class OldStyle(ActionPerformer):
    """Written for the first performer API: settings_keys and keywords."""

    settings_keys: ClassVar[frozenset[str]] = frozenset({"speed"})

    def __init__(self, *args: Any, speed: float = 1.0, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        if speed <= 0:
            raise ValueError(f"speed must be > 0, got {speed}")
        self.speed = speed
        self.cancelled: list[str] = []

    async def execute(self, goal: ActionGoal) -> str:
        await self.clock.sleep(2.0 / self.speed)
        return "moved"

    async def on_cancel(self, goal: ActionGoal) -> None:
        self.cancelled.append(goal.full_name)
        await asyncio.sleep(0)
'''

MISSION = f"""\
name: third_party
domain: {DOMAIN}
knowledge:
  instances: {{r1: robot, hall: room, kitchen: room}}
  predicates: ["(connected hall kitchen)", "(robot_at r1 hall)"]
  functions: ["(= (travel_time hall kitchen) 3)"]
goal: (robot_at r1 kitchen)
performers:
  - kind: gripper
    name: g1
    actions: {{move: [r1]}}
    force: FORCE
  - {{kind: oldstyle, name: o1, actions: {{move: [r1]}}, speed: 2}}
clock: {{kind: virtual}}
"""


def test_third_party_performers_old_and_new_shape(installed: Any, tmp_path: Path) -> None:
    from plansys_bridge.mission import run_mission

    installed(
        "acme-robots",
        {"acme_robots": THIRD_PARTY},
        {
            GROUPS["performers"]: {
                "gripper": "acme_robots:Gripper",
                "oldstyle": "acme_robots:OldStyle",
            }
        },
    )
    path = tmp_path / "m.yaml"
    path.write_text(MISSION.replace("FORCE", "-3"))
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert str(err.value).startswith(f"{path}:12:5: performers[0].force: ")
    assert "greater than 0, got -3" in str(err.value)
    path.write_text(MISSION.replace("FORCE", "12"))
    report = run_mission(load_mission(path), out=None)
    assert report.success, report.summary()
    assert report.result is not None
    assert {a.performer for a in report.result.actions} <= {"g1", "o1"}


def test_old_style_performer_keeps_its_api(installed: Any, virtual_hub: Any) -> None:
    """``from_config`` with settings_keys keywords, ``execute``, ``on_cancel``."""
    import asyncio

    from plansys_bridge.hub.auction import ActionClient
    from plansys_bridge.performers.base import PerformerContext

    installed(
        "old-robots",
        {"old_robots": THIRD_PARTY},
        {GROUPS["performers"]: {"old": "old_robots:OldStyle"}},
    )
    cls = PERFORMERS.load("old")
    context = PerformerContext(virtual_hub, virtual_hub.clock)
    entry = {"kind": "old", "name": "o1", "actions": {"move": ["r1"]}, "speed": 0.5}
    with pytest.raises(ConfigError) as err:
        cls.from_config({**entry, "sped": 1}, context, key="performers[3]")
    assert err.value.key == "performers[3].sped"
    with pytest.raises(ConfigError, match="speed must be > 0"):
        cls.from_config({**entry, "speed": -1}, context, key="performers[3]")
    [performer] = cls.from_config(entry, context, key="performers[3]")
    assert performer.speed == 0.5  # type: ignore[attr-defined]

    async def scenario() -> tuple[bool, bool, list[str]]:
        await performer.start()
        done = await ActionClient(virtual_hub, "move", ("r1", "a", "b")).run()
        client = ActionClient(virtual_hub, "move", ("r1", "b", "c"))
        task = asyncio.ensure_future(client.run())
        while not performer.busy:
            await virtual_hub.clock.sleep(0.1)
        client.cancel()
        cancelled = await task
        await virtual_hub.clock.sleep(0.5)
        await performer.stop()
        return done.success, cancelled.cancelled, performer.cancelled  # type: ignore[attr-defined]

    from plansys_bridge.clock import run

    success, cancelled, calls = run(scenario(), virtual_hub.clock)
    assert success and cancelled
    assert calls == ["(move r1 b c)"]


TRANSPORT_PLUGIN = """
from pydantic import Field

from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.hub.transport_kinds import TransportKind
from plansys_bridge.plugins import PluginSettings


class Loopback(TransportKind):
    class Settings(PluginSettings):
        queue: int = Field(8, ge=1)

    def create(self, context):
        return InProcessTransport()
"""


def test_third_party_transport(installed: Any, tmp_path: Path) -> None:
    installed(
        "acme-bus",
        {"acme_bus": TRANSPORT_PLUGIN},
        {
            GROUPS["transports"]: {"loopback": "acme_bus:Loopback"},
        },
    )
    base = (
        MISSION.replace("FORCE", "1").replace("gripper", "simulated").replace("    force: 1\n", "")
    )
    base = base.replace("  - {kind: oldstyle, name: o1, actions: {move: [r1]}, speed: 2}\n", "")
    path = tmp_path / "m.yaml"
    path.write_text(base + "transport: {kind: loopback, queue: 0}\n")
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert str(err.value).startswith(f"{path}:13:29: transport.queue: ")
    path.write_text(base + "transport: {kind: loopback, queue: 4}\n")
    kind = load_mission(path).transport_kind()
    assert type(kind).__name__ == "Loopback" and not kind.distributed
    assert isinstance(kind.create(TransportContext()), InProcessTransport)


SENSOR_PLUGIN = """
import asyncio

from pydantic import Field

from plansys_bridge.plugins import PluginSettings
from plansys_bridge.sensing.expressions import parse_expression
from plansys_bridge.sensing.source import SensingSource


class Thermometer(SensingSource):
    \"\"\"Plays back ``readings`` (degrees Celsius), one every ``period`` seconds.\"\"\"

    class Settings(PluginSettings):
        readings: list[float]
        period: float = Field(1.0, gt=0)

    def check(self, site):
        return frozenset({"celsius"})

    def value(self):
        return parse_expression("celsius")

    def attach(self, performer, feed):
        async def play():
            for reading in self.settings.readings:
                await asyncio.sleep(self.settings.period)
                feed({"celsius": reading})

        return asyncio.get_running_loop().create_task(play()).cancel
"""

SENSED_MISSION = """\
sensing:
  - {from: thermo, period: 0.25, readings: READINGS,
     when: "celsius > 30", predicate: "(visited r1 hall)"}
"""


def test_third_party_sensing_source_is_found_and_used(installed: Any, tmp_path: Path) -> None:
    """A sensing source from another distribution: its rule keys are checked by its
    Settings model when the mission loads, and its samples reach the knowledge."""
    from plansys_bridge.mission import build_knowledge, load_domain, run_mission

    installed(
        "acme-sensors",
        {"acme_sensors": SENSOR_PLUGIN},
        {GROUPS["sensing_sources"]: {"thermo": "acme_sensors:Thermometer"}},
    )
    assert "thermo" in SENSING_SOURCES.names()
    base = (
        MISSION.replace("FORCE", "1").replace("gripper", "simulated").replace("    force: 1\n", "")
    )
    base = base.replace("  - {kind: oldstyle, name: o1, actions: {move: [r1]}, speed: 2}\n", "")
    path = tmp_path / "m.yaml"
    cases = [
        ("[20, hot]", "hot", "sensing[0].readings[1]: Input should be a valid number, got 'hot'"),
        ("[20],\n     ratee: 2", "2,", "sensing[0].ratee: unknown key for a thermo rule (allowed:"),
    ]
    for readings, anchor, expected in cases:
        text = base + SENSED_MISSION.replace("READINGS", readings)
        path.write_text(text)
        mission = load_mission(path)
        with pytest.raises(ConfigError) as err:
            build_knowledge(mission, load_domain(mission))
        offset = text.index(anchor, text.index("sensing:"))
        line, column = text.count("\n", 0, offset) + 1, offset - text.rfind("\n", 0, offset)
        assert str(err.value).startswith(f"{path}:{line}:{column}: {expected}"), str(err.value)
    path.write_text(base + SENSED_MISSION.replace("READINGS", "[20, 35]"))
    report = run_mission(load_mission(path), out=None)
    assert report.success, report.summary()
    assert any("+(visited r1 hall) (sensed)" in e for e in report.events_applied), report.summary()
    assert issubclass(SENSING_SOURCES.load("thermo"), SensingSource)


@pytest.mark.parametrize(
    ("transport", "clock", "expected"),
    [
        ("{kind: dsd}", "virtual", "9:13: transport.kind: unknown transport 'dsd' (known: "),
        ("{kind: inprocess, domain_id: 3}", "virtual", "transport.domain_id: domain_id applies to"),
        ("{kind: dds, domain_id: 300}", "wall", "transport.domain_id: Input should be less"),
        ("{kind: dds}", "virtual", "clock.kind: the dds transport needs the wall clock"),
        ("{kind: dds, peer: [a]}", "wall", "transport.peer: unknown key (allowed: config, "),
    ],
)
def test_transport_section_is_validated_by_its_plugin(
    tmp_path: Path, transport: str, clock: str, expected: str
) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(
        f"domain: {DOMAIN}\ngoal: (robot_at r1 hall)\nknowledge: {{instances: {{r1: robot}}}}\n"
        "performers:\n  - {kind: simulated, name: s, actions: [move]}\n"
        f"clock: {{kind: {clock}}}\n\n\ntransport: {transport}\n"
    )
    with pytest.raises(ConfigError) as err:
        load_mission(path)
    assert expected in str(err.value)
    assert str(err.value).startswith(f"{path}:")


def test_dds_kind_builds_its_cyclone_configuration(tmp_path: Path) -> None:
    kind = DdsKind(DdsKind.Settings(domain_id=7, interfaces=["127.0.0.1"]))
    assert kind.distributed and kind.wall_clock_only and kind.dds_domain == 7
    assert '<Domain Id="7">' in kind.cyclone_config(tmp_path)
    (tmp_path / "cyclone.xml").write_text("<CycloneDDS/>")
    with_file = DdsKind(validate_settings(DdsKind.Settings, {"config": "cyclone.xml"}))
    assert with_file.cyclone_config(tmp_path) == "<CycloneDDS/>"
    with pytest.raises(ConfigError) as err:
        validate_settings(DdsKind.Settings, {"config": "c.xml", "peers": ["h"]}, key="transport")
    assert "replaces peers" in str(err.value)


def test_converted_builtin_performers_declare_settings_models() -> None:
    """The performers whose settings are pydantic models (the others still use the
    older ``settings_keys`` shape, which keeps working)."""
    from plansys_bridge.performers.entry import has_settings_model

    for name in ("can", "mavlink", "ros1_move_base"):
        assert has_settings_model(PERFORMERS.load(name)), name


def test_a_missing_module_is_told_apart_from_a_missing_package(installed: Any) -> None:
    """``pkg.missing_module:X`` with pkg installed names the module (also for a package
    that is one of our extras); only a package that is not installed is a dependency."""
    pytest.importorskip("can", reason="needs python-can installed (the can extra)")
    installed(
        "acme-typos",
        {
            "acme_typos": "",
            "acme_inner": "import can.no_such_interface\n",
            "acme_needs": "import acme_not_installed_anywhere\n",
        },
        {
            GROUPS["performers"]: {
                "own": "acme_typos.missing_module:Gripper",
                "extra": "can.no_such_module:Gripper",
                "inner": "acme_inner:Gripper",
                "needs": "acme_needs:Gripper",
            }
        },
    )
    expected = {
        "own": "points at acme_typos.missing_module:Gripper: no module named "
        "'acme_typos.missing_module' (is the entry point misspelt?)",
        "extra": "no module named 'can.no_such_module' (is the entry point misspelt?)",
        "inner": "no module named 'can.no_such_interface' (acme_inner imports it)",
        "needs": "needs the optional dependency 'acme_not_installed_anywhere'; "
        "install the package that provides 'acme_not_installed_anywhere'",
    }
    for name, words in expected.items():
        with pytest.raises(PluginError) as err:
            PERFORMERS.load(name)
        assert words in str(err.value), str(err.value)
        if name != "needs":
            assert "install" not in str(err.value)


class _Grip(plugins.DirectSettings):
    force: float = Field(10.0, gt=0)


class _Arm(plugins.DirectSettings):
    grip: _Grip = Field(default_factory=_Grip)
    reach: float = 1.0


def test_direct_settings_built_from_code_raise_config_error_with_the_whole_key_path() -> None:
    assert _Arm(grip={"force": 3.0}).grip.force == 3.0
    with pytest.raises(ConfigError) as err:
        _Arm(grip={"force": -1.0})
    assert err.value.key == "grip.force"
    with pytest.raises(ConfigError) as err:
        _Grip(forse=1.0)
    assert err.value.key == "forse" and "unknown key (allowed: force)" in str(err.value)
    # a failed construction leaves nothing behind: the next one is checked afresh
    assert _Grip(force=2.0).force == 2.0


def test_direct_settings_validated_by_the_loader_keep_pydantics_error_for_its_placing() -> None:
    from pydantic import ValidationError

    with pytest.raises(ValidationError):
        _Arm.model_validate({"grip": {"force": -1.0}}, context={})
    with pytest.raises(ConfigError) as err:
        validate_settings(_Arm, {"grip": {"force": -1.0}}, key="performers[2]")
    assert err.value.key == "performers[2].grip.force"
