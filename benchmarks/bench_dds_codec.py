"""The hub's ActionExecution bytes vs Cyclone DDS's own serialiser, per sample.

An auction among N bidders over DDS writes and reads N RESPONSEs and N-1 REJECTs,
all wrapped (``plansys_bridge_msgs/ActionExecution``). This measures, per sample,
what the DDS transport spends turning such a hub message into its XCDR1 bytes and
back (:mod:`plansys_bridge.hub.dds_execution`), against the peer: the same sample
as the generated Cyclone ``IdlStruct`` serialised with ``serialize`` and read back
with ``deserialize`` (what the Python binding does without this project's codec;
building the IdlStruct from the hub message is not counted). Both sides make the
same bytes (checked before timing). CPU time, best of ``--repeat`` runs.

Run: ``python benchmarks/bench_dds_codec.py [--bidders 200] [--repeat 7] [--json]``
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from typing import Any

from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds_codec import ROUTES, wire_sources
from plansys_bridge.hub.dds_wire import wire_codec


def _auction(bidders: int, round_: int) -> list[hm.ActionExecution]:
    """One auction's RESPONSEs and REJECTs (a new request id per auction, as live)."""
    request = f"plan/{round_}/0"
    args = ("r1", "a", "b")
    responses = [
        hm.ActionExecution(
            hm.ExecutionType.RESPONSE, f"p{i}", "move", args, bid=float(i), request_id=request
        )
        for i in range(bidders)
    ]
    reject = hm.ActionExecution(hm.ExecutionType.REJECT, "", "move", args, request_id=request)
    return responses + [hm.readdressed(reject, f"p{i}") for i in range(1, bidders)]


def cyclone_bytes(samples: list[Any]) -> list[bytes]:
    """The peer: Cyclone's serialiser, XCDR1 as the transport writes."""
    return [s.serialize(use_version_2=False) for s in samples]


def _per_sample(work: Callable[[], object], samples: int, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        work()
        best = min(best, time.process_time() - t0)
    return best / samples * 1e6


def measure(bidders: int, repeat: int) -> dict[str, Any]:
    route = ROUTES[hm.Topics.ACTIONS_HUB]
    write = route.to_bytes[1]
    channel = route.project
    assert write is not None and channel is not None
    read = channel.read
    cls = channel.idl_type
    encode = wire_codec(channel.ros_type).encode
    auctions = [_auction(bidders, r) for r in range(5)]
    messages = [m for a in auctions for m in a]
    samples = [cls.deserialize(encode(wire_sources(route.hub_topic, m)[1])) for m in messages]
    data = [write(m) for m in messages]
    if data != cyclone_bytes(samples):
        raise RuntimeError("the hub's bytes differ from Cyclone's")
    if [read(d) for d in data] != messages:
        raise RuntimeError("a message does not come back as it was written")
    n = len(messages)
    figures = {
        "hub_write_us": _per_sample(lambda: [write(m) for m in messages], n, repeat),
        "cyclone_serialize_us": _per_sample(lambda: cyclone_bytes(samples), n, repeat),
        "hub_read_us": _per_sample(lambda: [read(d) for d in data], n, repeat),
        "cyclone_deserialize_us": _per_sample(lambda: list(map(cls.deserialize, data)), n, repeat),
    }
    figures["write_ratio"] = figures["hub_write_us"] / figures["cyclone_serialize_us"]
    figures["read_ratio"] = figures["hub_read_us"] / figures["cyclone_deserialize_us"]
    return {"bidders": bidders, "samples": n, **figures}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bidders", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=7, help="runs per figure (best kept)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    row = measure(args.bidders, args.repeat)
    if args.json:
        print(json.dumps(row, indent=2))
        return
    print(f"ActionExecution (wrapped) per sample, {row['samples']} samples of 5 auctions, CPU us")
    print(f"{'':8} {'hub':>8} {'cyclone':>8} {'ratio':>7}")
    for what, hub, peer in (
        ("write", "hub_write_us", "cyclone_serialize_us"),
        ("read", "hub_read_us", "cyclone_deserialize_us"),
    ):
        print(f"{what:8} {row[hub]:>8.2f} {row[peer]:>8.2f} {row[hub] / row[peer]:>7.2f}")


if __name__ == "__main__":
    main()
