"""Auction round-trip latency on the real clock (in-process transport).

Measures, over many actions run back to back:

* REQUEST -> executing: from ``ActionClient.run()`` sending the REQUEST to the
  performer's ``execute()`` starting (REQUEST, RESPONSE, CONFIRM and the task start);
* FINISH -> notified: from the performer sending FINISH to ``run()`` returning;
* dispatch: from the predecessor's FINISH to the successor's ``execute()`` starting,
  when the successor's auction starts as soon as the predecessor's client returns
  (what a plan's next action sees; the executor adds its own tree tick on top).

Run: ``python benchmarks/bench_dispatch.py [--actions N] [--idle-performers K] [--json]``
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

from bench_support import StampingPerformer, summary

from plansys_bridge.clock import WallClock, run
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext


async def _bench(actions: int, idle: int, selection: str) -> dict[str, dict[str, float]]:
    hub = Hub(InProcessTransport(), WallClock())
    await hub.start()
    ctx = PerformerContext(hub, hub.clock)
    worker = StampingPerformer(ctx, "worker", {"move": ["r1"]})
    # performers for other robots: they see every REQUEST and must decline it
    others = [StampingPerformer(ctx, f"other{i}", {"move": [f"r{i + 2}"]}) for i in range(idle)]
    for p in (worker, *others):
        await p.start()
    policy = AuctionPolicy(selection=selection, bid_window=0.0)  # type: ignore[arg-type]
    request_to_exec: list[float] = []
    finish_to_client: list[float] = []
    dispatch: list[float] = []
    previous_finish: float | None = None
    for i in range(actions + 50):
        rid = str(i)
        client = ActionClient(hub, "move", ("r1", "a", "b"), request_id=rid, policy=policy)
        sent = time.perf_counter()
        outcome = await client.run()
        returned = time.perf_counter()
        if not outcome.success:
            raise RuntimeError(f"action {i} failed: {outcome.status}")
        started, finished = worker.started[rid], worker.finished[rid]
        if i >= 50:  # warm-up excluded
            request_to_exec.append(started - sent)
            finish_to_client.append(returned - finished)
            if previous_finish is not None:
                dispatch.append(started - previous_finish)
        previous_finish = finished
    for p in (worker, *others):
        await p.stop()
    await hub.close()
    return {
        "request_to_executing": summary(request_to_exec),
        "finish_to_client": summary(finish_to_client),
        "finish_to_successor_executing": summary(dispatch),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--actions", type=int, default=2000)
    parser.add_argument("--idle-performers", type=int, default=10)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    results: dict[str, Any] = {}
    for selection in ("first", "best_bid"):
        for idle in (0, args.idle_performers):
            rule = "best_bid (window 0)" if selection == "best_bid" else selection
            key = f"{rule}, {idle} other performers"
            results[key] = run(_bench(args.actions, idle, selection), WallClock())
    if args.json:
        print(json.dumps(results, indent=2))
        return
    print(f"Auction latency on the wall clock, in-process transport, {args.actions} actions each")
    header = f"{'case':<42} {'measure':<30} {'median':>9} {'p90':>9} {'p99':>9} {'max':>9}  (us)"
    print(header)
    print("-" * len(header))
    for case, measures in results.items():
        for name, s in measures.items():
            print(
                f"{case:<42} {name:<30} {s['median_us']:>9.1f} {s['p90_us']:>9.1f} "
                f"{s['p99_us']:>9.1f} {s['max_us']:>9.1f}"
            )


if __name__ == "__main__":
    main()
