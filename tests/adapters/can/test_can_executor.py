"""The CAN mission (configs/can_base.yaml) through planner and executor, virtual bus and clock.

Two simulated bases on two virtual buses, the performers built from the mission file
through the ``can`` entry point. Shows a plan of moves running both bases at once,
a drive fault ending the plan with the base's own words, and a battery frame that
turns low in the middle of a move halting it through the knowledge base.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from can_rig import new_channel
from plansys_bridge_adapters.can.performer import CanBasePerformer
from rosbags.highlevel import AnyReader

from plansys_bridge.clock import run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.execution.results import ExecutionResult
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.mission import build_knowledge, run_mission
from plansys_bridge.mission_config import MissionConfig, load_mission
from plansys_bridge.pddl.model import Domain
from plansys_bridge.pddl.parser import parse_domain_files
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.registry import performers_from_config
from plansys_bridge.planning.plan import Plan
from plansys_bridge.planning.planner import Planner

MISSION = Path(__file__).resolve().parents[3] / "configs" / "can_base.yaml"


@dataclass
class Mission:
    config: MissionConfig
    domain: Domain
    knowledge: ProblemExpert


def load() -> Mission:
    config = load_mission(MISSION)
    domain = parse_domain_files(config.domain_paths)
    return Mission(config, domain, build_knowledge(config, domain))


Body = Callable[[Executor, dict[str, CanBasePerformer]], Awaitable[ExecutionResult]]


def execute(mission: Mission, hub: Hub, body: Body, **options: Any) -> ExecutionResult:
    """Start the mission's performers (on fresh channels), run ``body``, stop them."""

    async def main() -> ExecutionResult:
        await hub.start()
        entries = [
            dict(p.model_dump()) | {"bus": {"interface": "virtual", "channel": new_channel()}}
            for p in mission.config.performers
        ]
        context = PerformerContext(
            hub=hub,
            clock=hub.clock,
            knowledge=mission.knowledge,
            base_dir=mission.config.base_dir,
        )
        performers = performers_from_config(entries, context)
        started: dict[str, CanBasePerformer] = {}
        try:
            for performer in performers:
                assert isinstance(performer, CanBasePerformer)
                await performer.start()
                started[performer.robot] = performer
            executor = Executor(
                hub, mission.domain, mission.knowledge, None, ExecutorOptions(**options)
            )
            return await body(executor, started)
        finally:
            for performer in started.values():
                await performer.stop()
            await hub.close()

    return run(main(), hub.clock)


def plan_for(mission: Mission) -> Plan:
    planned = Planner(timeout=20).solve(mission.domain, mission.knowledge.to_problem())
    assert planned.plan is not None, planned.message
    return planned.plan


def test_mission_plan_drives_both_bases_in_parallel(hub: Hub) -> None:
    mission = load()
    plan = plan_for(mission)

    async def body(executor: Executor, bases: dict[str, CanBasePerformer]) -> ExecutionResult:
        return await executor.execute(plan, goal=mission.knowledge.get_goal())

    result = execute(mission, hub, body, max_replans=0)
    assert result.success, (
        result.status,
        result.message,
        [(a.text, a.message) for a in result.actions],
    )
    assert mission.knowledge.is_goal_satisfied()
    assert {a.performer for a in result.actions} == {"base_r2d2", "base_bb8"}
    assert all(a.message.startswith("arrived at ") for a in result.actions)
    # The two bases drove at the same time: more than one action-second per second.
    assert result.efficiency() > 1.0
    # Battery levels came from the status frames.
    for robot in ("r2d2", "bb8"):
        battery = mission.knowledge.get_function("battery", (robot,))
        assert battery is not None and 90.0 < battery < 100.0


def test_drive_fault_fails_the_plan_with_the_base_status(hub: Hub) -> None:
    mission = load()
    plan = plan_for(mission)

    async def body(executor: Executor, bases: dict[str, CanBasePerformer]) -> ExecutionResult:
        double = bases["r2d2"].double
        assert double is not None
        asyncio.get_running_loop().call_later(3.0, lambda: double.set_faults(motor=True))
        return await executor.execute(plan, goal=mission.knowledge.get_goal())

    result = execute(mission, hub, body, max_replans=0)
    assert not result.success
    failed = [a for a in result.actions if a.status == ActionStatus.FAILED]
    assert len(failed) == 1
    assert failed[0].text.startswith("(move r2d2")
    assert "base fault: motor fault" in failed[0].message


def test_low_battery_frame_halts_the_move_through_the_knowledge(hub: Hub) -> None:
    mission = load()
    plan = plan_for(mission)
    stops: list[bool] = []

    async def body(executor: Executor, bases: dict[str, CanBasePerformer]) -> ExecutionResult:
        double = bases["bb8"].double
        assert double is not None
        loop = asyncio.get_running_loop()
        loop.call_later(3.0, lambda: double.set_battery(12.0))
        result = await executor.execute(plan, goal=mission.knowledge.get_goal())
        await hub.clock.sleep(2.0)  # the cancelled base confirms its stop meanwhile
        stops.append(double.model.moving)
        assert double.counters.estop_commands == 0
        assert abs(double.model.y - 3.0) > 0.3  # it never got to the bedroom
        return result

    result = execute(mission, hub, body, max_replans=0)
    assert not result.success
    assert mission.knowledge.exist_predicate("(battery_low bb8)")
    halted = [
        a
        for a in result.actions
        if a.status == ActionStatus.FAILED
        and "over all requirement (not (battery_low bb8)) no longer holds" in a.message
    ]
    assert len(halted) == 1, "\n".join(
        f"{a.text} {a.status.name} {a.message}" for a in result.actions
    )
    assert stops == [False]  # the halted move was cancelled on the base, which stopped


def test_mission_runner_records_the_bases_odometry(tmp_path: Path) -> None:
    """``plansys-bridge run configs/can_base.yaml --record``, as the CLI runs it."""
    bag = tmp_path / "run"
    report = run_mission(load_mission(MISSION).model_copy(update={"record": str(bag)}), out=None)
    assert report.success, report.summary()
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == "/r2d2/pose"]
        assert conns and conns[0].msgtype == "geometry_msgs/msg/PoseStamped"
        poses: list[Any] = [
            reader.deserialize(raw, conns[0].msgtype) for _, _, raw in reader.messages(conns)
        ]
    # 10 poses per mission second over a run of about 25 s, ending back at the dock.
    assert len(poses) > 150
    last = poses[-1]
    assert last.header.frame_id == "odom"
    assert abs(last.pose.position.x) < 0.05 and abs(last.pose.position.y) < 0.05
