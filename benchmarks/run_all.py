"""Run every benchmark briefly and write ``benchmarks/RESULTS.md``.

Each benchmark runs as its own process with short settings (a few seconds to a
minute each), and its printed table goes into the results verbatim: the figures
with their peer's figure from the same run and the ratio, where the benchmark has a
peer. The file starts with the machine the figures come from (processor, cores,
memory, Python, operating system) and the date; a benchmark that cannot run here
(a missing corpus, bag or tool) is listed with the reason it gave.

Run: ``python benchmarks/run_all.py [--only NAME ...] [--out benchmarks/RESULTS.md]``
(the whole set takes about ten minutes on two cores).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Bench:
    name: str
    script: str
    args: tuple[str, ...]
    what: str
    timeout: float = 600.0


BENCHES = (
    Bench(
        "cli_startup",
        "bench_cli_startup.py",
        ("--runs", "5"),
        "whole-process CPU time of `--help` of the tool and each command vs `python -c pass`",
    ),
    Bench(
        "cli_process",
        "bench_cli_process.py",
        ("--runs", "3"),
        "`validate` and `plan` as whole processes vs the `pddl` library and `kairos solve`",
    ),
    Bench(
        "auction_scale",
        "bench_auction_scale.py",
        ("--auctions", "10", "--repeat", "2"),
        "one auction with 10/50/100/200 bidders, in-process and over DDS, vs linear cost",
    ),
    Bench(
        "executor_scale",
        "bench_executor_scale.py",
        ("--sizes", "500", "1000", "2000", "--robots", "10"),
        "executing 500/1000/2000 actions with 10 robots (virtual clock), vs the smallest",
    ),
    Bench(
        "executor_overhead",
        "bench_executor_overhead.py",
        ("--sizes", "100", "300", "1000"),
        "the executor's CPU per action with performers that cost nothing (virtual clock)",
    ),
    Bench(
        "knowledge_per_action",
        "bench_knowledge_per_action.py",
        ("--repeat", "3", "--calls"),
        "the knowledge's share of an executed action (the executor's calls replayed)",
    ),
    Bench(
        "validation_share",
        "bench_validation_share.py",
        ("--repeat", "10"),
        "validate_plan's share of knowledge -> plan",
    ),
    Bench(
        "dispatch",
        "bench_dispatch.py",
        ("--actions", "300"),
        "auction round trip and predecessor FINISH -> successor executing",
    ),
    Bench(
        "executor_dispatch",
        "bench_executor_dispatch.py",
        ("--actions", "200"),
        "the same through the executor's tree",
    ),
    Bench("graph", "bench_graph.py", ("--sizes", "100", "1000", "--repeat", "1"), "graph + tree"),
    Bench("dds", "bench_dds.py", ("--n", "300", "--warmup", "50"), "DDS vs in-process round trip"),
    Bench(
        "dds_codec",
        "bench_dds_codec.py",
        ("--repeat", "5"),
        "ActionExecution bytes per sample vs Cyclone DDS's own serialiser",
    ),
    Bench(
        "parse",
        "bench_parse.py",
        ("--repeat", "2", "--objects", "2000"),
        "PDDL parsing vs the `pddl` package and unified-planning",
    ),
    Bench(
        "knowledge",
        "knowledge_bench.py",
        ("--rooms", "500", "--steps", "1000", "--closure", "100"),
        "knowledge layer",
    ),
    Bench(
        "planners",
        "bench_planners.py",
        ("--quick", "--timeout", "5"),
        "every available solver on the same tasks",
    ),
    Bench(
        "cooking",
        "bench_cooking.py",
        ("--seeds", "8", "--hours", "0.25"),
        "Table I: efficiency per robot count over seeds, vs the paper",
        timeout=1200.0,
    ),
    Bench(
        "cooking_wall",
        "bench_cooking.py",
        (
            "--seeds",
            "8",
            "--hours",
            "0.1",
            "--robots",
            "3",
            "--clock",
            "wall",
            "--time-scale",
            "0.05",
        ),
        "Table I with 3 robots on the wall clock, every duration 20x shorter",
        timeout=1200.0,
    ),
    Bench("mavlink", "bench_mavlink.py", (), "MAVLink adapter against the vehicle double"),
    Bench(
        "sitl",
        "bench_sitl.py",
        (),
        "MAVLink adapter against ArduPilot SITL, vs raw pymavlink on the same SITL",
        timeout=1200,
    ),
    Bench("can", "bench_can.py", (), "CAN adapter on python-can's virtual bus"),
    Bench("bag_replay", "bench_bag_replay.py", (), "ROS bag reading and replay"),
    Bench(
        "ros1",
        "bench_ros1.py",
        ("--latency-n", "200", "--burst-n", "1000"),
        "TCPROS vs rospy against a real roscore; latency the bridge adds",
    ),
)


def machine() -> list[str]:
    """What the figures were measured on."""
    cpu = platform.processor() or "unknown processor"
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        for line in cpuinfo.read_text(errors="replace").splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    memory = ""
    meminfo = Path("/proc/meminfo")
    if meminfo.is_file():
        first = meminfo.read_text(errors="replace").splitlines()[0].split()
        if len(first) >= 2 and first[1].isdigit():
            memory = f", {int(first[1]) / 1024 / 1024:.1f} GiB memory"
    load = ""
    if hasattr(os, "getloadavg"):
        load = " (load average {:.2f} {:.2f} {:.2f} at the start)".format(*os.getloadavg())
    return [
        f"- date: {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}",
        f"- processor: {cpu}, {os.cpu_count()} logical cores{memory}{load}",
        f"- Python {platform.python_version()} ({platform.python_implementation()}), "
        f"{platform.platform()}",
    ]


def run_one(bench: Bench) -> tuple[str, float, str]:
    """(status, seconds, output) of one benchmark run."""
    command = [sys.executable, str(HERE / bench.script), *bench.args]
    started = time.perf_counter()
    try:
        done = subprocess.run(
            command,
            cwd=HERE.parent,
            capture_output=True,
            text=True,
            timeout=bench.timeout,
            check=False,
        )
    except subprocess.TimeoutExpired as exc:
        partial = exc.stdout if isinstance(exc.stdout, str) else ""
        return f"stopped after {bench.timeout:g} s", time.perf_counter() - started, partial
    took = time.perf_counter() - started
    output = done.stdout.rstrip()
    if done.returncode != 0:
        tail = "\n".join(done.stderr.strip().splitlines()[-3:])
        return f"failed (exit {done.returncode}): {tail}", took, output
    return "ok", took, output


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=[b.name for b in BENCHES])
    parser.add_argument("--out", type=Path, default=HERE / "RESULTS.md")
    args = parser.parse_args()
    chosen = [b for b in BENCHES if not args.only or b.name in args.only]
    lines = [
        "# Benchmark results",
        "",
        "Written by `python benchmarks/run_all.py` (short settings; each benchmark's own",
        "options give longer runs). Figures come with their peer's figure from the same",
        "run and the ratio where the benchmark has a peer. Machine:",
        "",
        *machine(),
        "",
    ]
    for bench in chosen:
        print(f"{bench.name} ...", end=" ", flush=True)
        status, took, output = run_one(bench)
        print(f"{status.splitlines()[0]} ({took:.0f} s)", flush=True)
        command = " ".join(("python", f"benchmarks/{bench.script}", *bench.args))
        lines += [f"## {bench.name}: {bench.what}", "", f"`{command}` ({took:.0f} s)", ""]
        if status != "ok":
            lines += [f"Not measured here: {status}", ""]
        if output:
            lines += ["```", output, "```", ""]
    args.out.write_text("\n".join(lines), encoding="utf-8")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
