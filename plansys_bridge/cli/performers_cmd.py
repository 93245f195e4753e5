"""``plansys-bridge performers MISSION.yaml``: serve a mission's performers on its DDS hub.

The executor side runs elsewhere, e.g. ``plansys-bridge run MISSION.yaml
--no-performers`` in another process (or on another terminal) with the same mission
file, whose ``transport: {kind: dds, domain_id: N}`` puts both on one DDS domain.
The command prints one ``performers ready: ...`` line once every performer is
started, then serves auctions until interrupted (Ctrl-C, SIGTERM) or ``--duration``.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
from typing import TYPE_CHECKING, Any

from plansys_bridge.cli.options import check_positive

if TYPE_CHECKING:
    from plansys_bridge.clock import Clock
    from plansys_bridge.mission_config import MissionConfig
    from plansys_bridge.performers.base import ActionPerformer


def register(sub: Any) -> None:
    p = sub.add_parser(
        "performers",
        help="serve only a mission's performers on its DDS hub (the executor runs elsewhere)",
    )
    p.add_argument("mission", help="mission YAML file with transport: {kind: dds, domain_id: N}")
    p.add_argument("--time-scale", type=float, help="override clock.time_scale")
    p.add_argument(
        "--duration", type=float, help="stop after this many seconds (default: until interrupted)"
    )
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    check_positive(args.time_scale, "--time-scale")
    check_positive(args.duration, "--duration")
    # imported here: `--help` and the other commands never pay for missions and DDS
    from plansys_bridge.clock import run
    from plansys_bridge.mission import in_mission_file, make_clock
    from plansys_bridge.mission_config import load_mission

    mission = load_mission(args.mission)
    if not mission.transport_kind().distributed:
        raise mission.error(
            "performers in their own process need a transport between processes "
            "(transport: {kind: dds})",
            key="transport.kind",
        )
    if args.time_scale is not None:
        clock_config = type(mission.clock).model_validate(
            mission.clock.model_dump() | {"time_scale": args.time_scale}
        )
        mission = mission.model_copy(update={"clock": clock_config})
    clock = make_clock(mission)
    with in_mission_file(mission):
        run(_serve(mission, clock, args.duration), clock)
    return 0


async def _serve(mission: MissionConfig, clock: Clock, duration: float | None) -> None:
    import asyncio

    from plansys_bridge.hub.hub import Hub
    from plansys_bridge.mission import build_knowledge, load_domain, make_transport
    from plansys_bridge.mission.session import mission_bid_costs
    from plansys_bridge.performers.base import PerformerContext
    from plansys_bridge.performers.remote import serve_performers

    domain = load_domain(mission)
    knowledge = build_knowledge(mission, domain)
    hub = Hub(make_transport(mission, domain, role="performers"), clock)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    signals = (signal.SIGINT, signal.SIGTERM)
    for sig in signals:
        loop.add_signal_handler(sig, stop.set)
    await hub.start()
    try:
        context = PerformerContext(
            hub=hub,
            clock=clock,
            knowledge=knowledge,
            base_dir=mission.base_dir,
            bid_costs=mission_bid_costs(mission),
        )
        entries = [p.model_dump() for p in mission.performers]

        def ready(performers: list[ActionPerformer]) -> None:
            names = ", ".join(p.node_name for p in performers)
            print(f"performers ready: {names} ({hub.transport!r})", flush=True)

        async def until() -> None:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), duration)

        await serve_performers(
            context, entries, until(), on_ready=ready, say=lambda line: print(line, flush=True)
        )
    finally:
        await hub.close()
        for sig in signals:
            loop.remove_signal_handler(sig)
    print("performers stopped", flush=True)
