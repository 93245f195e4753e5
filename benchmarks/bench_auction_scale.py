"""One auction with N performers all bidding: is its cost linear in N?

N performers serve the same action and bid on every REQUEST (the worst case for an
auction: everybody answers). One :class:`ActionClient` runs ``--auctions`` actions
back to back with ``selection="best_bid"``; each auction is REQUEST, N RESPONSEs,
CONFIRM to the cheapest, N-1 REJECTs, then FINISH. The figure is the CPU time of
the process per auction (it counts every message delivery, and is less disturbed
than wall time by other work on a shared machine; ``ms`` is the mean of the best
run, ``median ms`` the median auction of all runs), with:

* ``inprocess``: one in-process transport on the virtual clock;
* ``dds``: the executor on one DdsTransport, the N performers on another, in one
  process (loopback), on the wall clock.

The peer figure printed beside each is the same measure at the smallest N scaled
linearly (``linear``): a ratio near 1 means cost linear in bidders.

Run: ``python benchmarks/bench_auction_scale.py [--bidders 10 50 100 200] [--auctions 20]
[--modes inprocess,dds] [--repeat 3] [--json]``
"""

from __future__ import annotations

import argparse
import asyncio
import gc
import json
import random
import statistics
import time
from typing import Any

from plansys_bridge.clock import VirtualClock, WallClock, run
from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport, Transport
from plansys_bridge.performers.base import ActionGoal, ActionPerformer, PerformerContext


class Bidder(ActionPerformer):
    """Bids a fixed cost and finishes at once."""

    def __init__(self, *args: Any, cost: float, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.cost = cost

    def bid(self, goal: ActionGoal) -> float | None:
        return self.cost

    async def execute(self, goal: ActionGoal) -> str | None:
        return None


async def _auctions(
    client_hub: Hub, performer_hub: Hub, bidders: int, auctions: int, window: float
) -> list[float]:
    """CPU seconds of each auction, after one warm-up auction."""
    ctx = PerformerContext(performer_hub, performer_hub.clock)
    costs = random.Random(bidders).sample(range(1, 10 * bidders + 1), bidders)
    performers = [
        Bidder(ctx, f"p{i}", {"move": []}, cost=float(c), heartbeat_period=1.0)
        for i, c in enumerate(costs)
    ]
    for p in performers:
        await p.start()
    policy = AuctionPolicy(selection="best_bid", bid_window=window, give_up_after=60.0)
    try:
        spent: list[float] = []
        for i in range(auctions + 1):
            t0 = time.process_time()
            client = ActionClient(client_hub, "move", ("r", "a", "b"), policy=policy)
            outcome = await client.run()
            if not outcome.success:
                raise RuntimeError(f"auction {i}: {outcome.status}")
            # let the REJECTs and heartbeats of this auction be delivered too
            for _ in range(3):
                await asyncio.sleep(0)
            if i:
                spent.append(time.process_time() - t0)
        return spent
    finally:
        for p in performers:
            await p.stop()


async def _dds(bidders: int, auctions: int) -> list[float]:
    from plansys_bridge.hub.dds import DdsTransport

    domain = random.SystemRandom().randint(1, 232)
    transports: list[Transport] = [DdsTransport(domain), DdsTransport(domain)]
    clock = WallClock()
    hubs = [Hub(t, clock) for t in transports]
    for h in hubs:
        await h.start()
    try:
        for t in transports:
            await t.wait_for_peers(1)  # type: ignore[attr-defined]
        await asyncio.sleep(0.3)  # let every reader match every writer
        return await _auctions(hubs[0], hubs[1], bidders, auctions, window=0.05)
    finally:
        for h in reversed(hubs):
            await h.close()


def measure(mode: str, bidders: int, auctions: int) -> list[float]:
    """CPU seconds of each of ``auctions`` auctions."""
    # The previous run's hub and performers are garbage with cycles: collected now,
    # not by a full collection inside one of this run's auctions.
    gc.collect()
    if mode == "inprocess":
        clock = VirtualClock()
        return run(_inprocess_with(clock, bidders, auctions), clock)
    return asyncio.run(_dds(bidders, auctions))


async def _inprocess_with(clock: VirtualClock, bidders: int, auctions: int) -> list[float]:
    hub = Hub(InProcessTransport(), clock)
    await hub.start()
    try:
        return await _auctions(hub, hub, bidders, auctions, window=0.01)
    finally:
        await hub.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bidders", type=int, nargs="+", default=[10, 50, 100, 200])
    parser.add_argument("--auctions", type=int, default=20)
    parser.add_argument("--modes", default="inprocess,dds")
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure (best kept)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows: list[dict[str, Any]] = []
    for mode in args.modes.split(","):
        base: float | None = None
        for n in args.bidders:
            # the best of a few runs: other work on a shared machine only adds time
            runs = [measure(mode, n, args.auctions) for _ in range(args.repeat)]
            per = min(statistics.fmean(r) for r in runs)
            # the median auction of all runs: what one auction costs, a burst of
            # other work on the machine counting for one auction only
            median = statistics.median(t for r in runs for t in r)
            if base is None:
                base = per / n
            linear = base * n
            rows.append(
                {
                    "mode": mode,
                    "bidders": n,
                    "ms_per_auction": per * 1e3,
                    "median_ms": median * 1e3,
                    "linear_ms": linear * 1e3,
                    "ratio": per / linear,
                }
            )
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    print(f"One auction, every performer bidding (CPU ms per auction, {args.auctions} auctions)")
    print(
        f"{'mode':<10} {'bidders':>8} {'ms':>10} {'median ms':>10} {'linear ms':>10} {'ratio':>7}"
    )
    for r in rows:
        print(
            f"{r['mode']:<10} {r['bidders']:>8} {r['ms_per_auction']:>10.3f} "
            f"{r['median_ms']:>10.3f} {r['linear_ms']:>10.3f} {r['ratio']:>7.2f}"
        )


if __name__ == "__main__":
    main()
