"""Behaviour-tree actions (PlanSys2's BTAction): BehaviorTree.CPP v4 XML on py_trees,
node types as plugins, on the mission clock."""

from __future__ import annotations

from pathlib import Path

import pytest
from bt_example_nodes import BT_NODES, HALTED
from py_trees.common import Status

from plansys_bridge.errors import ConfigError
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission
from plansys_bridge.performers.bt.build import build_tree
from plansys_bridge.performers.bt.nodes import BtContext, node_types
from plansys_bridge.performers.bt.xml_tree import BtXmlError, main_tree, parse_bt_xml

DATA = Path(__file__).resolve().parents[1] / "data"


class ManualClock:
    """Mission time moved by the test (trees read only ``now()``)."""

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t

    def advance(self, seconds: float) -> None:
        self.t += seconds


def _tree(xml: str, clock: ManualClock | None = None, **board: str):  # type: ignore[no-untyped-def]
    types = node_types() | BT_NODES
    ctx = BtContext(clock or ManualClock(), None, dict(board))
    return build_tree(main_tree(parse_bt_xml(xml, "t.xml")), types, ctx)


def _run(root, clock: ManualClock, ticks: int = 100) -> list[Status]:  # type: ignore[no-untyped-def]
    seen = []
    for _ in range(ticks):
        root.tick_once()
        seen.append(root.status)
        if root.status != Status.RUNNING:
            break
        clock.advance(0.5)
    return seen


def _xml(body: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="T">{body}</BehaviorTree></root>'


def test_control_nodes() -> None:
    clock = ManualClock()
    seq = _tree(_xml("<Sequence><OpenGripper/><ApproachObject/><CloseGripper/></Sequence>"), clock)
    assert _run(seq, clock) == [Status.RUNNING] * 5 + [Status.SUCCESS]
    fallback = _tree(
        _xml("<Fallback><AlwaysFailure/><Inverter><AlwaysFailure/></Inverter></Fallback>")
    )
    assert _run(fallback, clock) == [Status.SUCCESS]
    retry = _tree(
        _xml('<RetryUntilSuccessful num_attempts="4"><Flaky failures="2"/></RetryUntilSuccessful>')
    )
    BT_NODES["Flaky"].ticks = 0  # type: ignore[attr-defined]
    assert _run(retry, clock)[-1] == Status.SUCCESS
    BT_NODES["Flaky"].ticks = 0  # type: ignore[attr-defined]
    give_up = _tree(
        _xml('<RetryUntilSuccessful num_attempts="2"><Flaky failures="5"/></RetryUntilSuccessful>')
    )
    assert _run(give_up, clock)[-1] == Status.FAILURE
    timeout = _tree(_xml('<Timeout msec="1000"><Wait seconds="5"/></Timeout>'), clock)
    statuses = _run(timeout, clock)
    assert statuses[-1] == Status.FAILURE and len(statuses) == 3  # 0, 0.5, 1.0 s


def test_reactive_sequence_rechecks_its_condition_and_halts_the_action() -> None:
    clock = ManualClock()
    HALTED.clear()
    guarded = _tree(
        _xml(
            "<ReactiveSequence><Inverter><AlwaysFailure/></Inverter>"
            '<Move name="mv" goal="{arg2}"/></ReactiveSequence>'
        ),
        clock,
        arg2="kitchen",
    )
    guarded.tick_once()
    assert guarded.status == Status.RUNNING
    guarded.stop(Status.INVALID)  # a cancel halts the running node
    assert HALTED == ["mv kitchen"]


@pytest.mark.parametrize(
    ("xml", "message"),
    [
        (_xml("<Sequence><Movee/></Sequence>"), "t.xml:1:55: <Movee>: unknown node type 'Movee'"),
        (_xml('<Move goal="a" speed="2"/>'), "unknown port(s) speed of Move"),
        (_xml("<Move/>"), "Move needs port(s) goal"),
        (_xml("<Sequence/>"), "a control node needs at least one child"),
        (_xml('<Condition ID="Move" goal="x"/>'), "Move is an action node, not a condition"),
        (_xml('<Timeout msec="soon"><Move goal="x"/></Timeout>'), "msec must be a number"),
        ('<root BTCPP_format="3"><BehaviorTree/></root>', "only format 4 is read"),
        ("<root><BehaviorTree ID='T'><Sequence></root>", "t.xml:1:40: not well-formed XML"),
    ],
)
def test_bad_trees_name_file_line_and_column(xml: str, message: str) -> None:
    with pytest.raises(BtXmlError) as error:
        _tree(xml)
    assert message in str(error.value)


MISSION = """
name: bt_factory
domain: {domain}
knowledge:
  instances: {{r2d2: robot, wheels_zone: zone, assembly_zone: zone, wheel_1: piece}}
  predicates:
    - (robot_at r2d2 assembly_zone)
    - (robot_available r2d2)
    - (battery_full r2d2)
    - (piece_at wheel_1 wheels_zone)
goal: (and (piece_at wheel_1 assembly_zone))
performers:
  - kind: bt
    name: r2d2_bt
    actions: {{move: [r2d2], transport: [r2d2]}}
    trees: {{move: {data}/bt/move.xml, transport: {data}/bt/transport.xml}}
    plugins: [bt_example_nodes]
    tick_period: 0.5
clock: {{kind: virtual}}
replanning: {{max_replans: 0}}
{events}
"""


def _mission(tmp_path: Path, events: str = "") -> Path:
    path = tmp_path / "bt.yaml"
    path.write_text(MISSION.format(domain=DATA / "bt_example.pddl", data=DATA, events=events))
    return path


def test_a_mission_with_bt_actions(tmp_path: Path) -> None:
    lines: list[str] = []
    report = run_mission(load_mission(_mission(tmp_path)), out=lines.append)
    assert report.success, report.summary()
    assert report.result is not None
    done = [(a.text, a.performer) for a in report.result.actions]
    assert done == [
        ("(move r2d2 assembly_zone wheels_zone)", "r2d2_bt"),
        ("(transport r2d2 wheel_1 wheels_zone assembly_zone)", "r2d2_bt"),
    ]
    move, transport = report.result.actions
    # Move takes 2 s of mission time, ticked every 0.5 s
    assert move.execution_time == pytest.approx(2.0, abs=0.6)
    # transport: grippers, five ticks approaching, then the 2 s move
    assert transport.execution_time > move.execution_time
    assert transport.message == "behavior tree returned SUCCESS"


def test_a_failing_condition_fails_the_action_naming_the_node(tmp_path: Path) -> None:
    events = "events:\n  - {at: 1.0, remove_predicate: (battery_full r2d2)}\n"
    report = run_mission(load_mission(_mission(tmp_path, events)), out=None)
    assert not report.success and report.result is not None
    move = report.result.actions[0]
    assert move.status == ActionStatus.FAILED
    assert move.message.startswith("behavior tree returned FAILURE at battery_ok")


def test_bad_tree_in_a_mission_names_key_and_line(tmp_path: Path) -> None:
    bad = tmp_path / "move.xml"
    bad.write_text(_xml("<Sequence>\n<Moove goal='{arg2}'/></Sequence>"))
    path = _mission(tmp_path)
    path.write_text(path.read_text().replace(f"{DATA}/bt/move.xml", str(bad)))
    with pytest.raises(ConfigError) as error:
        run_mission(load_mission(path), out=None)
    text = str(error.value)
    assert "performers[0].trees.move" in text and f"{bad}:2:1: <Moove>: unknown node type" in text


@pytest.mark.parametrize(
    ("old", "new", "key", "message"),
    [
        ("tick_period: 0.5", "tick_period: -1", "tick_period", "greater than 0"),
        ("plugins: [bt_example_nodes]", "plugins: bt_example_nodes", "plugins", "valid list"),
        (f"transport: {DATA}/bt/transport.xml", "fly: x.xml", "trees.fly", "not one of"),
        (f", transport: {DATA}/bt/transport.xml", "", "trees", "no tree file for transport"),
    ],
)
def test_bad_settings_are_load_errors_with_line(
    tmp_path: Path, old: str, new: str, key: str, message: str
) -> None:
    """The settings model and the trees-per-action check run when the mission loads,
    before any tree file is read."""
    path = _mission(tmp_path)
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))
    with pytest.raises(ConfigError) as error:
        load_mission(path)
    assert error.value.key == f"performers[0].{key}", str(error.value)
    assert error.value.file == str(path) and error.value.line is not None
    line = path.read_text().splitlines()[error.value.line - 1]
    assert line.strip().startswith(key.split(".")[0]), line
    assert message in str(error.value)
