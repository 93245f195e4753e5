"""``plansys-bridge bridge BRIDGE.yaml``: bridge ROS 1 and ROS 2 topics until interrupted.

Prints one line per bridged topic once the bridge is up, then, when stopped (Ctrl-C,
SIGTERM or ``--duration``), how many messages crossed on each.
"""

from __future__ import annotations

import argparse
import contextlib
from typing import Any

from plansys_bridge.cli.options import check_positive


def register(sub: Any) -> None:
    p = sub.add_parser("bridge", help="bridge ROS 1 and ROS 2 topics (no ros1_bridge needed)")
    p.add_argument("config", help="bridge YAML file: ros1, ros2 and topics")
    p.add_argument(
        "--duration", type=float, help="stop after this many seconds (default: until interrupted)"
    )
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    check_positive(args.duration, "--duration")
    import asyncio  # here: `--help` never loads the event loop machinery

    from plansys_bridge.bridge.config import load_bridge_config

    config = load_bridge_config(args.config)
    asyncio.run(_run(config, args.duration))
    return 0


async def _run(config: Any, duration: float | None) -> None:
    import asyncio

    from plansys_bridge.bridge.bridge import Bridge

    async with Bridge(config) as bridge:
        print(
            f"bridging ROS 1 {config.master_uri} <-> ROS 2 domain {config.domain_id}:", flush=True
        )
        for stats in bridge.stats:
            print(f"  {stats.describe()}", flush=True)
        try:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(asyncio.Event().wait(), duration)
        finally:
            for stats in bridge.stats:
                print(
                    f"{stats.describe()}: {stats.forwarded} forwarded"
                    + (f", {stats.skipped} over the rate limit" if stats.skipped else "")
                    + (f", {stats.failed} failed" if stats.failed else ""),
                    flush=True,
                )
