"""``plansys-bridge serve MISSION.yaml``: this executor as PlanSys2's ROS 2 nodes on DDS.

Runs the mission's hub and performers (as ``run`` does, without planning or executing
anything by itself) and serves, on a Cyclone DDS domain with ROS 2's names and types:
the problem expert's services (``/problem_expert/*``) on the mission's knowledge, the
domain expert's getters (``/domain_expert/*``), the planner's ``/planner/get_plan`` and
the executor's ``/execute_plan`` action. A ROS 2 PlanSys2 client (the terminal, a
ProblemExpertClient, an ExecutePlan action client) on the same domain drives it. The
domain is the mission's ``transport.domain_id`` when it runs on DDS, else
``--domain-id`` (default 0, ROS 2's). Stops on Ctrl-C or SIGTERM (or ``--duration``).
"""

from __future__ import annotations

import argparse
import contextlib
import signal
from typing import TYPE_CHECKING, Any

from plansys_bridge.cli.options import check_positive

if TYPE_CHECKING:  # imported when the command runs: --help stays light
    from plansys_bridge.clock import WallClock
    from plansys_bridge.mission_config import MissionConfig


def register(sub: Any) -> None:
    p = sub.add_parser(
        "serve",
        help="serve PlanSys2's expert services, get_plan and the ExecutePlan action on DDS",
    )
    p.add_argument("mission", help="mission YAML file (domain, knowledge, performers)")
    p.add_argument("--domain-id", type=int, help="DDS domain (default: the mission's, else 0)")
    p.add_argument(
        "--duration", type=float, help="stop after this many seconds (default: until interrupted)"
    )
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    from plansys_bridge.clock import WallClock, run
    from plansys_bridge.mission import in_mission_file
    from plansys_bridge.mission_config import load_mission

    check_positive(args.duration, "--duration")
    mission = load_mission(args.mission)
    domain_id = args.domain_id
    if domain_id is None:
        domain_id = mission.transport_kind().dds_domain or 0
    clock = WallClock()  # ROS 2 clients wait in real time
    with in_mission_file(mission):
        run(_serve(mission, clock, domain_id, args.duration), clock)
    return 0


async def _serve(
    mission: MissionConfig, clock: WallClock, domain_id: int, duration: float | None
) -> None:
    import asyncio

    from plansys_bridge.execution.executor import Executor
    from plansys_bridge.hub.dds_config import loopback_config
    from plansys_bridge.mission import MissionSession, build_knowledge
    from plansys_bridge.pddl.parser import parse_domain_files
    from plansys_bridge.planning.planner import Planner
    from plansys_bridge.ros2.domain_planner_services import serve_domain_expert, serve_planner
    from plansys_bridge.ros2.executor_action import ExecutePlanServer
    from plansys_bridge.ros2.node import Ros2Node
    from plansys_bridge.ros2.problem_expert_services import serve_problem_expert

    domain = parse_domain_files(mission.domain_paths)
    knowledge = build_knowledge(mission, domain)
    planner = Planner()
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    signals = (signal.SIGINT, signal.SIGTERM)
    for sig in signals:
        loop.add_signal_handler(sig, stop.set)
    node: Ros2Node | None = None
    try:
        async with MissionSession(mission, domain, knowledge, clock) as session:
            # Cyclone opens a domain once per process: share the hub's configuration.
            transport = session.hub.transport
            config = getattr(transport, "config", None)
            if getattr(transport, "domain_id", None) != domain_id or not isinstance(config, str):
                config = loopback_config(domain_id)
            node = Ros2Node(domain_id, config=config, name="plansys_bridge")
            await node.start()
            executor = Executor(session.hub, domain, knowledge, planner, mission.executor_options())
            services = [
                serve_problem_expert(node, knowledge),
                serve_domain_expert(node, knowledge.domain_expert),
                serve_planner(node, planner),
            ]
            action = ExecutePlanServer(node, executor)
            count = sum(len(s.servers) for s in services)
            print(
                f"serving {count} services and /execute_plan on DDS domain {domain_id} "
                f"({len(session.performers)} performers)",
                flush=True,
            )
            try:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(stop.wait(), duration)
            finally:
                executor.cancel()
                await action.close()
                for service_set in services:
                    await service_set.close()
    finally:
        if node is not None:
            await node.close()
        for sig in signals:
            loop.remove_signal_handler(sig)
    print("stopped", flush=True)
