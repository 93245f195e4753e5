"""Plain progress lines about performers: one that stops or comes back gets a line,
its every READY and RUNNING does not (real performers on an in-process hub, virtual
clock)."""

from __future__ import annotations

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.monitoring.progress import ProgressLines
from plansys_bridge.monitoring.watch import MissionWatch
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer


def test_a_performer_that_stops_and_comes_back_gets_a_line_each_time() -> None:
    hub = Hub(InProcessTransport(), VirtualClock())
    lines: list[str] = []

    def performer(name: str) -> SimulatedPerformer:
        return SimulatedPerformer(
            PerformerContext(hub, hub.clock), name, {"move": []}, default_duration=2.0
        )

    async def main() -> None:
        await hub.start()
        watch = MissionWatch(hub.clock.now, ProgressLines(lines.append, hub.clock.now))
        watch.attach(hub)
        r1, r2 = performer("r1"), performer("r2")
        await r1.start()
        await r2.start()
        await hub.clock.sleep(1.5)
        outcome = await ActionClient(hub, "move", ("a", "b"), request_id="0").run()
        assert outcome.success
        await r1.stop()
        await hub.clock.sleep(1.5)
        await r1.start()
        await hub.clock.sleep(1.5)
        await r1.stop()
        await r2.stop()
        watch.close()
        await hub.close()

    run(main(), hub.clock)
    performers = [line.split("] ", 1)[1] for line in lines if "PERFORMER" in line]
    assert performers == [
        "PERFORMER r1 not_ready",
        "PERFORMER r1 ready",
        "PERFORMER r1 not_ready",
        "PERFORMER r2 not_ready",
    ]
