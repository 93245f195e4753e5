"""``plansys-bridge monitor [--domain-id N]``: watch a mission running in another process.

Joins the mission's DDS domain (``transport: {kind: dds, domain_id: N}`` in its
mission file) as a listener only, and shows what goes over the hub: each plan as it
starts, every action's state and completion, the performer that won each auction,
the performers' heartbeats and the knowledge. On a terminal it is a live table
(rich); piped or with ``--plain``, one line per change. It never publishes, so it
can come and go while the mission runs; the plan and the knowledge are kept by DDS
for late joiners (transient-local), the rest shows from the next message on.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from plansys_bridge.cli.options import check_at_least, check_positive
from plansys_bridge.cli.output import say


def register(sub: Any) -> None:
    p = sub.add_parser("monitor", help="live view of a mission running in another process (DDS)")
    p.add_argument("--domain-id", type=int, default=0, help="the mission's transport.domain_id")
    p.add_argument(
        "--duration", type=float, help="stop after this many seconds (default: until Ctrl-C)"
    )
    p.add_argument("--plain", action="store_true", help="plain lines even on a terminal")
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    from plansys_bridge.clock import WallClock, run
    from plansys_bridge.errors import ConfigError
    from plansys_bridge.hub.hub import Hub
    from plansys_bridge.monitoring.live import make_live_view
    from plansys_bridge.monitoring.watch import MissionWatch

    check_positive(args.duration, "--duration")
    check_at_least(args.domain_id, 0, "--domain-id")
    try:
        from plansys_bridge.hub.dds import DdsTransport
    except ImportError as exc:
        raise ConfigError(
            f"monitor needs cyclonedds (pip install 'plansys-bridge[dds]'): {exc}",
            key="monitor",
        ) from exc
    clock = WallClock()
    t0 = clock.now()

    def elapsed() -> float:
        return clock.now() - t0

    live = sys.stdout.isatty() and not args.plain and not args.quiet
    view = make_live_view(elapsed, f"DDS domain {args.domain_id}") if live else None
    listener = view if view is not None else MonitorLines(say, elapsed)
    hub = Hub(DdsTransport(args.domain_id), clock)

    async def watch_hub() -> None:
        await hub.start()
        watch = MissionWatch(clock.now, listener).attach(hub)
        if view is not None:
            view.bind(watch)
        try:
            if view is not None:
                with view:
                    await _wait(args.duration)
            else:
                say(f"monitoring DDS domain {args.domain_id} (Ctrl-C to stop)")
                await _wait(args.duration)
        finally:
            watch.close()
            await hub.close()

    run(watch_hub(), clock)
    return 0


async def _wait(duration: float | None) -> None:
    import asyncio

    if duration is not None:
        await asyncio.sleep(duration)
    else:
        await asyncio.Event().wait()


class MonitorLines:
    """Plain lines for ``monitor``: the progress lines of ``run`` (first plan included)
    plus performers appearing or changing state and knowledge changes."""

    def __init__(self, out: Any, elapsed: Any) -> None:
        from plansys_bridge.monitoring.progress import ProgressLines

        self.out = out
        self.elapsed = elapsed
        self.progress = ProgressLines(out, elapsed, first_plan=True)
        self._knowledge: tuple[int, int, str] | None = None

    def __call__(self, event: Any) -> None:
        t = f"[{self.elapsed():8.1f}]"
        if event.kind == "performer" and event.performer is not None:
            p = event.performer
            self.out(f"{t} performer {p.name}: {p.state.name}")
        elif event.kind == "knowledge":
            self._on_knowledge(t, event)
        else:
            self.progress(event)

    def _on_knowledge(self, t: str, event: Any) -> None:
        k = event.knowledge
        if k is None:
            return
        summary = (len(k.instances), len(k.predicates), k.goal)
        if summary != self._knowledge:
            self._knowledge = summary
            self.out(f"{t} knowledge: {summary[0]} instances, {summary[1]} facts, goal {k.goal}")
