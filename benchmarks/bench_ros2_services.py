"""ROS 2 service round trip and action goal -> accepted latency over DDS loopback.

Measured in one process, two participants, after a warm-up:

* ``service``: the project's :class:`ServiceClient` calls ``/problem_expert/get_problem_instances``
  served by :func:`serve_problem_expert` (a knowledge of ``--instances`` objects), from
  writing the request to the reply reaching the caller on the asyncio loop;
* ``goal``: the project's :class:`ActionClient` sends a NavigateToPose goal to an
  :class:`ActionServer`; from the send_goal request to the ``accepted`` reply;
* ``raw``: the peer's figure, a bare Cyclone DDS request/reply of the same sizes
  (``sequence<octet>`` payloads as long as the service's request and reply), echoed by
  a DDS thread and awaited with a wait set: what DDS itself costs.

Run: ``python benchmarks/bench_ros2_services.py [--n 500] [--instances 50] [--json]``
"""

import argparse
import asyncio
import json
import random
import statistics
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int64, sequence, uint8
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from plansys_bridge.hub.dds_config import loopback_config
from plansys_bridge.hub.dds_participant import SharedDomain
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.ros2.actions import GOAL_STATUS, ActionClient, ActionServer
from plansys_bridge.ros2.node import SERVICES_QOS, Ros2Node
from plansys_bridge.ros2.problem_expert_services import serve_problem_expert
from plansys_bridge.ros2.services import ServiceClient, wire_types

DOMAIN = """(define (domain bench) (:requirements :typing) (:types robot)
  (:predicates (ready ?r - robot)))"""


@dataclass
class Blob(IdlStruct, typename="bench::Blob"):
    seq: int64 = 0
    data: sequence[uint8] = field(default_factory=list)


def percentiles(samples: list[float]) -> dict[str, float]:
    ms = sorted(s * 1000 for s in samples)
    return {
        "median_ms": statistics.median(ms),
        "p95_ms": ms[int(len(ms) * 0.95) - 1],
        "mean_ms": statistics.fmean(ms),
    }


def serialized_size(sample: Any) -> int:
    return len(sample.serialize()) - 4  # without the encapsulation header


async def bench_service(domain: int, n: int, warmup: int, instances: int) -> tuple[dict, int, int]:
    knowledge = ProblemExpert(parse_domain(DOMAIN))
    for i in range(instances):
        knowledge.add_instance(f"robot{i}", "robot")
    server_node, client_node = Ros2Node(domain, name="srv"), Ros2Node(domain, name="cli")
    await server_node.start()
    await client_node.start()
    services = serve_problem_expert(server_node, knowledge)
    srv = "plansys2_msgs/srv/GetProblemInstances"
    client = ServiceClient(client_node, "/problem_expert/get_problem_instances", srv)
    try:
        await client.wait_for_service()
        times = []
        reply = None
        for i in range(warmup + n):
            t0 = time.perf_counter()
            reply = await client.call()
            if i >= warmup:
                times.append(time.perf_counter() - t0)
        request_type, _ = wire_types(srv)
        sizes = (serialized_size(request_type()), serialized_size(reply))
    finally:
        await client.close()
        await services.close()
        await client_node.close()
        await server_node.close()
    return percentiles(times), *sizes


async def bench_goal(domain: int, n: int, warmup: int) -> dict:
    nav = "nav2_msgs/action/NavigateToPose"
    result = dds_type(f"{nav}_Result")

    async def execute(_handle: Any) -> tuple[int, Any]:
        return GOAL_STATUS["STATUS_SUCCEEDED"], result()

    server_node, client_node = Ros2Node(domain, name="srv"), Ros2Node(domain, name="cli")
    await server_node.start()
    await client_node.start()
    server = ActionServer(server_node, "navigate_to_pose", nav, execute)
    client = ActionClient(client_node, "navigate_to_pose", nav)
    goal = dds_type(f"{nav}_Goal")()
    try:
        await client.wait_for_server()
        times = []
        for i in range(warmup + n):
            t0 = time.perf_counter()
            handle = await client.send_goal(goal)
            elapsed = time.perf_counter() - t0
            assert handle.accepted
            await handle.result()
            if i >= warmup:
                times.append(elapsed)
    finally:
        await client.close()
        await server.close()
        await client_node.close()
        await server_node.close()
    return percentiles(times)


def bench_raw(domain: int, n: int, warmup: int, request_size: int, reply_size: int) -> dict:
    """Bare Cyclone request/reply with payloads of the service's sizes."""
    qos = SERVICES_QOS.qos()
    a, b = DomainParticipant(domain), DomainParticipant(domain)
    req_w = DataWriter(a, Topic(a, "rq/bench/rawRequest", Blob), qos)
    rep_r = DataReader(a, Topic(a, "rr/bench/rawReply", Blob), qos)
    req_r = DataReader(b, Topic(b, "rq/bench/rawRequest", Blob), qos)
    rep_w = DataWriter(b, Topic(b, "rr/bench/rawReply", Blob), qos)
    any_state = SampleState.Any | ViewState.Any | InstanceState.Any
    stop = threading.Event()
    payload = [7] * max(0, reply_size - 12)

    def echo() -> None:
        ws = WaitSet(b)
        ws.attach(ReadCondition(req_r, any_state))
        while not stop.is_set():
            ws.wait(duration(milliseconds=100))
            for s in req_r.take(N=16):
                rep_w.write(Blob(s.seq, payload))

    thread = threading.Thread(target=echo, daemon=True)
    thread.start()
    ws = WaitSet(a)
    ws.attach(ReadCondition(rep_r, any_state))
    while (
        req_w.get_publication_matched_status().current_count == 0
        or rep_r.get_subscription_matched_status().current_count == 0
    ):
        time.sleep(0.01)
    request = [1] * max(0, request_size - 12)
    times = []
    for i in range(warmup + n):
        t0 = time.perf_counter()
        req_w.write(Blob(i, request))
        got = False
        while not got:
            ws.wait(duration(seconds=1))
            got = any(s.seq == i for s in rep_r.take(N=16))
        if i >= warmup:
            times.append(time.perf_counter() - t0)
    stop.set()
    thread.join()
    return percentiles(times)


async def main_async(args: argparse.Namespace) -> dict[str, Any]:
    domain = random.SystemRandom().randint(1, 232)
    # Every participant of the run, the bare ones too, on the loopback-only configuration.
    SharedDomain.acquire(domain, loopback_config(domain))
    try:
        service, request_size, reply_size = await bench_service(
            domain, args.n, args.warmup, args.instances
        )
        goal = await bench_goal(domain, args.n, args.warmup)
        raw = await asyncio.to_thread(
            bench_raw, domain, args.n, args.warmup, request_size, reply_size
        )
    finally:
        SharedDomain.release(domain)
    return {
        "n": args.n,
        "instances": args.instances,
        "request_bytes": request_size,
        "reply_bytes": reply_size,
        "service": service,
        "goal_accepted": goal,
        "raw_cyclone": raw,
        "service_vs_raw": service["median_ms"] / raw["median_ms"],
        "goal_vs_raw": goal["median_ms"] / raw["median_ms"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=500)
    parser.add_argument("--warmup", type=int, default=50)
    parser.add_argument("--instances", type=int, default=50)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    out = asyncio.run(main_async(args))
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print(
        f"payload: request {out['request_bytes']} B, reply {out['reply_bytes']} B "
        f"({out['instances']} instances), {out['n']} round trips each"
    )
    for name, key in (
        ("get_problem_instances", "service"),
        ("goal -> accepted", "goal_accepted"),
        ("raw Cyclone req/rep", "raw_cyclone"),
    ):
        r = out[key]
        print(f"  {name:24s} median {r['median_ms']:.3f} ms  p95 {r['p95_ms']:.3f} ms")
    print(
        f"  ratio to raw Cyclone: service {out['service_vs_raw']:.2f}x, "
        f"goal {out['goal_vs_raw']:.2f}x"
    )


if __name__ == "__main__":
    main()
