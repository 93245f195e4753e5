"""Round-trip latency of an ActionExecution: DdsTransport vs InProcessTransport.

One side publishes a REQUEST on ``actions_hub``; an echo subscriber answers each with
a RESPONSE; the time from publishing the REQUEST to the RESPONSE callback running on
the asyncio loop is one round trip (two hub messages, each with its project wrapper
on DDS). Measured back to back, after a warm-up:

* ``inprocess``: one InProcessTransport, echo in the same loop;
* ``dds-local``: two DdsTransports (two participants) in one process;
* ``dds-process``: the echo runs in a subprocess on its own DdsTransport (loopback UDP).

Run: ``python benchmarks/bench_dds.py [--n 2000] [--modes inprocess,dds-local,dds-process]
[--json]``
"""

from __future__ import annotations

import argparse
import asyncio
import json
import random
import statistics
import subprocess
import sys
import time
from typing import Any

from plansys_bridge.hub.messages import ActionExecution, ExecutionType, Topics
from plansys_bridge.hub.transport import InProcessTransport, Transport

REQUEST = ActionExecution(ExecutionType.REQUEST, "", "move", ("r1", "a", "b"), request_id="b:0")


def echo(transport: Transport) -> None:
    """Answer every REQUEST with a RESPONSE (as an idle performer would)."""

    def on_msg(msg: object) -> None:
        if isinstance(msg, ActionExecution) and msg.type == ExecutionType.REQUEST:
            transport.publish(
                Topics.ACTIONS_HUB,
                ActionExecution(
                    ExecutionType.RESPONSE,
                    "echo",
                    msg.action,
                    msg.arguments,
                    request_id=msg.request_id,
                    bid=1.0,
                ),
            )

    transport.subscribe(Topics.ACTIONS_HUB, on_msg)


async def ping(transport: Transport, n: int, warmup: int) -> list[float]:
    """Round trips in seconds (``n`` of them, after ``warmup`` unmeasured ones)."""
    loop = asyncio.get_running_loop()
    waiter: asyncio.Future[float] | None = None

    def on_msg(msg: object) -> None:
        if (
            isinstance(msg, ActionExecution)
            and msg.type == ExecutionType.RESPONSE
            and waiter is not None
            and not waiter.done()
        ):
            waiter.set_result(time.perf_counter())

    transport.subscribe(Topics.ACTIONS_HUB, on_msg)
    samples: list[float] = []
    for i in range(warmup + n):
        waiter = loop.create_future()
        t0 = time.perf_counter()
        transport.publish(Topics.ACTIONS_HUB, REQUEST)
        t1 = await asyncio.wait_for(waiter, 5.0)
        if i >= warmup:
            samples.append(t1 - t0)
    return samples


async def run_inprocess(n: int, warmup: int) -> list[float]:
    t = InProcessTransport()
    await t.start()
    echo(t)
    try:
        return await ping(t, n, warmup)
    finally:
        await t.close()


async def run_dds_local(n: int, warmup: int) -> list[float]:
    from plansys_bridge.hub.dds import DdsTransport

    domain = random.SystemRandom().randint(1, 232)
    a, b = DdsTransport(domain), DdsTransport(domain)
    await a.start()
    await b.start()
    try:
        await a.wait_for_peers(1)
        await b.wait_for_peers(1)
        echo(b)
        return await ping(a, n, warmup)
    finally:
        await b.close()
        await a.close()


async def run_dds_process(n: int, warmup: int) -> list[float]:
    from plansys_bridge.hub.dds import DdsTransport

    domain = random.SystemRandom().randint(1, 232)
    proc = subprocess.Popen(
        [sys.executable, __file__, "--echo", str(domain)], stdin=subprocess.PIPE, text=True
    )
    a = DdsTransport(domain)
    await a.start()
    try:
        await a.wait_for_peers(1, timeout=30)
        await asyncio.sleep(0.2)  # let the echo's writer match our reader too
        return await ping(a, n, warmup)
    finally:
        await a.close()
        assert proc.stdin is not None
        proc.stdin.close()  # the echo process exits when its stdin closes
        proc.wait(timeout=10)


async def serve_echo(domain: int) -> None:
    from plansys_bridge.hub.dds import DdsTransport

    t = DdsTransport(domain)
    await t.start()
    echo(t)
    try:
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)
    finally:
        await t.close()


def summary(samples: list[float]) -> dict[str, float]:
    us = sorted(s * 1e6 for s in samples)
    return {
        "n": len(us),
        "median_us": round(statistics.median(us), 1),
        "p99_us": round(us[min(len(us) - 1, int(0.99 * len(us)))], 1),
        "max_us": round(us[-1], 1),
    }


MODES = {"inprocess": run_inprocess, "dds-local": run_dds_local, "dds-process": run_dds_process}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=2000, help="measured round trips per mode")
    parser.add_argument("--warmup", type=int, default=100)
    parser.add_argument("--modes", default=",".join(MODES))
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--echo", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.echo is not None:
        asyncio.run(serve_echo(args.echo))
        return
    results: dict[str, Any] = {}
    for mode in args.modes.split(","):
        results[mode] = summary(asyncio.run(MODES[mode](args.n, args.warmup)))
    if args.json:
        print(json.dumps(results, indent=2))
        return
    print(f"ActionExecution round trip (REQUEST -> RESPONSE), {args.n} samples per mode")
    for mode, r in results.items():
        print(
            f"  {mode:<12} median {r['median_us']:8.1f} us   p99 {r['p99_us']:8.1f} us"
            f"   max {r['max_us']:8.1f} us"
        )


if __name__ == "__main__":
    main()
