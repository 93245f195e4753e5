"""FINISH -> next action running, over DDS, against a raw Cyclone write -> read.

The chain of ``bench_executor_dispatch.py`` (N ``step`` actions, each needing the
previous one's at-end effect) runs with the executor on one DdsTransport and the
performer on another (two DDS participants in one process, loopback). For each pair
of consecutive actions it measures, with ``time.perf_counter``, the time from the
performer sending FINISH of one action to its ``execute()`` starting the next: the
FINISH crosses DDS, the executor applies effects and starts the successor, and the
auction crosses DDS three times (REQUEST, RESPONSE, CONFIRM), each hub message with
its project wrapper.

The peer figure, from the same run: a raw Cyclone DDS write -> read of the same
``plansys2_msgs/ActionExecution`` sample between two participants (writer in one,
reader blocked on a wait set in the other), no project code in between. The ratio is
dispatch / one raw hop; dispatch needs at least four hops.

Run: ``python benchmarks/bench_dds_dispatch.py [--actions 300] [--raw 2000] [--json]``
"""

from __future__ import annotations

import argparse
import json
import random
import time
from typing import Any

from bench_executor_dispatch import chain_task
from bench_support import StampingPerformer, summary
from cyclonedds.core import Policy, Qos, ReadCondition, SampleState, WaitSet
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from plansys_bridge.clock import WallClock, run
from plansys_bridge.execution.executor import Executor
from plansys_bridge.execution.options import ExecutorOptions
from plansys_bridge.hub.dds import DdsTransport
from plansys_bridge.hub.dds_config import loopback_config
from plansys_bridge.hub.hub import Hub
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.performers.base import PerformerContext


async def _dispatch(actions: int, domain_id: int) -> dict[str, float]:
    domain, knowledge, plan = chain_task(actions)
    clock = WallClock()
    executor_transport = DdsTransport(domain_id)
    performer_transport = DdsTransport(domain_id)
    executor_hub, performer_hub = Hub(executor_transport, clock), Hub(performer_transport, clock)
    await executor_hub.start()
    await performer_hub.start()
    await executor_transport.wait_for_peers(1)
    await performer_transport.wait_for_peers(1)
    performer = StampingPerformer(
        PerformerContext(performer_hub, clock), "worker", {"step": ["r1"]}
    )
    await performer.start()
    try:
        executor = Executor(
            executor_hub, domain, knowledge, None, ExecutorOptions(publish_dot=False)
        )
        result = await executor.execute(plan, plan_id="chain")
    finally:
        await performer.stop()
        await performer_hub.close()
        await executor_hub.close()
    if not result.success:
        raise RuntimeError(f"chain failed: {result.message}")
    warmup = min(20, actions // 10)
    return summary(
        [
            performer.started[f"chain/0/{i}"] - performer.finished[f"chain/0/{i - 1}"]
            for i in range(1 + warmup, actions)
        ]
    )


def _raw(n: int, domain_id: int) -> dict[str, float]:
    """One-way latency of a raw Cyclone write -> read between two participants."""
    domain = Domain(domain_id, loopback_config(domain_id))
    sample_type = dds_type("plansys2_msgs/msg/ActionExecution")
    qos = Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.History.KeepLast(100),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )
    a, b = DomainParticipant(domain_id), DomainParticipant(domain_id)
    writer = DataWriter(a, Topic(a, "rt/actions_hub", sample_type), qos)
    reader = DataReader(b, Topic(b, "rt/actions_hub", sample_type), qos)
    waitset = WaitSet(b)
    waitset.attach(ReadCondition(reader, SampleState.Any))
    deadline = time.monotonic() + 10
    while writer.get_publication_matched_status().current_count < 1:
        if time.monotonic() > deadline:
            raise RuntimeError("raw participants did not match")
        time.sleep(0.01)
    sample = sample_type(type=6, node_id="worker", action="step", arguments=["r1", "s0", "s1"])
    latencies = []
    for i in range(n + n // 10):
        start = time.perf_counter()
        writer.write(sample)
        while not reader.take(N=1):
            waitset.wait(duration(seconds=1))
        if i >= n // 10:
            latencies.append(time.perf_counter() - start)
    for entity in (writer, reader, waitset, a, b):
        entity.__del__()
    del domain
    return summary(latencies)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--actions", type=int, default=300)
    parser.add_argument("--raw", type=int, default=2000)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rng = random.SystemRandom()
    dispatch_domain, raw_domain = rng.sample(range(1, 233), 2)
    results: dict[str, Any] = {
        "finish_to_next_running_dds": run(_dispatch(args.actions, dispatch_domain), WallClock()),
        "raw_cyclone_write_to_read": _raw(args.raw, raw_domain),
    }
    d, r = results["finish_to_next_running_dds"], results["raw_cyclone_write_to_read"]
    results["ratio_median"] = d["median_us"] / r["median_us"]
    if args.json:
        print(json.dumps(results, indent=2))
        return
    print(f"FINISH -> next action running over DDS ({args.actions} actions) vs raw Cyclone")
    header = f"{'measure':<30} {'median':>9} {'p90':>9} {'p99':>9} {'max':>9}  (us)"
    print(header)
    print("-" * len(header))
    for name in ("finish_to_next_running_dds", "raw_cyclone_write_to_read"):
        s = results[name]
        print(
            f"{name:<30} {s['median_us']:>9.1f} {s['p90_us']:>9.1f} "
            f"{s['p99_us']:>9.1f} {s['max_us']:>9.1f}"
        )
    print(
        f"ratio (median): {results['ratio_median']:.1f}x one raw hop "
        "(the dispatch needs at least 4: FINISH, REQUEST, RESPONSE, CONFIRM)"
    )


if __name__ == "__main__":
    main()
