"""The MAVLink adapter against real ArduPilot SITL (ArduCopter), next to raw pymavlink.

* survey: the shipped copter survey (``configs/mavlink_copter.yaml``) through the
  executor at speedups 1 / 5 / 10 on a fresh SITL each time: wall time, mission time,
  planned makespan (the plan's durations) vs flown makespan (first action start to
  last action end), and time to armable (connect to the EKF using GPS), in wall and
  simulated seconds;
* round trip: MAV_CMD_SET_MESSAGE_INTERVAL until its COMMAND_ACK, through the
  adapter's asyncio client (SERIAL0) and through raw pymavlink (SERIAL1) on the same
  SITL at speedup 1 after it has booted, median and p99 in ms, and their ratio;
* fault -> FINISH(failure): another ground station switches the flying copter to
  LOITER; milliseconds from its HEARTBEAT showing LOITER to the action's FINISH.

Needs ``PLANSYS_BRIDGE_SITL_DIR`` (a folder with ``arducopter`` and ``copter.parm``);
without it the benchmark says so and exits 0.

Run: ``python benchmarks/bench_sitl.py [--json] [--speedups 1,5,10] [--round-trips 200]``
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench_support import percentile
from plansys_bridge_adapters.mavlink.errors import WaitTimeout
from plansys_bridge_adapters.mavlink.sitl import SitlProcess, instance_free, missing, sitl_dir
from plansys_bridge_adapters.mavlink.vehicle import LinkSettings, MavlinkVehicle
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as ml

from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import mission_from_dict

TESTS = Path(__file__).resolve().parents[1] / "tests" / "adapters" / "mavlink"
sys.path.insert(0, str(TESTS))  # the tests' second ground station and mission helpers

import yaml  # noqa: E402
from sitl_support import GroundStation, finish_cli, sitl_mission, start_cli  # noqa: E402


def _instance() -> int:
    return next(n for n in range(20, 60) if instance_free(n))


def _start(workdir: Path, speedup: float) -> SitlProcess:
    return SitlProcess("copter", _instance(), workdir, speedup=speedup, folder=sitl_dir()).start()


async def _time_to_armable(url: str) -> float:
    v = MavlinkVehicle(url, LinkSettings(connect_timeout=60))
    start = time.monotonic()
    await v.connect()
    try:
        await v.wait_ekf(600)
        return time.monotonic() - start
    finally:
        await v.close()


def survey(speedup: float, workdir: Path) -> dict[str, float]:
    """One survey on a fresh SITL; armable time measured on a second fresh one."""
    sitl = _start(workdir / f"armable{speedup:g}", speedup)
    try:
        armable = asyncio.run(_time_to_armable(sitl.url))
    finally:
        sitl.stop()
    sitl = _start(workdir / f"survey{speedup:g}", speedup)
    try:
        path = sitl_mission("mavlink_copter.yaml", {"uav1": sitl.url}, workdir)
        data = yaml.safe_load(path.read_text())
        mission = mission_from_dict(data, source=str(path), base_dir=path.parent)
        started = time.monotonic()
        report = run_mission(mission, out=None)
        wall = time.monotonic() - started
    finally:
        sitl.stop()
    result = report.result
    if not report.success or result is None:
        raise SystemExit(f"survey at speedup {speedup:g} failed: {report.summary()}")
    planned = result.plans[0].makespan
    starts = [a.start for a in result.actions if a.start is not None]
    ends = [a.end for a in result.actions if a.end is not None]
    flown = max(ends) - min(starts)
    return {
        "wall_s": wall,
        "mission_s": result.total_time,
        "planned_makespan_s": planned,
        "flown_makespan_s": flown,
        "flown_makespan_sim_s": flown * speedup,
        "time_to_armable_s": armable,
        "time_to_armable_sim_s": armable * speedup,
    }


def _raw_round_trips(url: str, n: int) -> list[float]:
    """The same command with plain pymavlink: send, then block on recv_match."""
    conn = mavutil.mavlink_connection(url, source_system=251, source_component=190)
    try:
        conn.wait_heartbeat(timeout=30)
        out = []
        for _ in range(n):
            t = time.perf_counter()
            conn.mav.command_long_send(
                1, 1, ml.MAV_CMD_SET_MESSAGE_INTERVAL, 0, 33, 100_000, 0, 0, 0, 0, 0
            )
            ack = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=5)
            if ack is None:
                raise SystemExit(f"{url}: no COMMAND_ACK within 5 s")
            out.append((time.perf_counter() - t) * 1000)
        return out
    finally:
        conn.close()


async def _adapter_round_trips(url: str, n: int) -> list[float]:
    """The command through the adapter's client, once SITL has finished booting (its
    main loop runs slower until "ArduPilot Ready": ~20 ms per ACK instead of ~6)."""
    v = MavlinkVehicle(url, LinkSettings(telemetry_hz={}, connect_timeout=60))
    await v.connect()
    try:
        with contextlib.suppress(WaitTimeout):
            ready = lambda: any("ArduPilot Ready" in e.text for e in v.statustexts)  # noqa: E731
            await v.wait_for(ready, 30, "ArduPilot Ready")
        out = []
        for _ in range(n):
            t = time.perf_counter()
            await v.command(ml.MAV_CMD_SET_MESSAGE_INTERVAL, 33, 100_000)
            out.append((time.perf_counter() - t) * 1000)
        return out
    finally:
        await v.close()


def round_trips(n: int, workdir: Path) -> dict[str, Any]:
    sitl = _start(workdir / "rtt", 1.0)
    try:
        adapter = asyncio.run(_adapter_round_trips(sitl.url, n))
        raw = _raw_round_trips(sitl.gcs_url, n)
    finally:
        sitl.stop()
    med_a, med_r = statistics.median(adapter), statistics.median(raw)
    return {
        "adapter_median_ms": med_a,
        "adapter_p99_ms": percentile(adapter, 0.99),
        "pymavlink_median_ms": med_r,
        "pymavlink_p99_ms": percentile(raw, 0.99),
        "ratio_median": med_a / med_r if med_r else float("nan"),
    }


def fault_latency(workdir: Path, speedup: float = 5.0) -> dict[str, float]:
    """Through ``plansys-bridge run``: HEARTBEAT showing LOITER -> the action's end."""
    sitl = _start(workdir / "fault", speedup)
    try:
        path = sitl_mission("mavlink_copter.yaml", {"uav1": sitl.url}, workdir)
        proc = start_cli(path)  # SITL opens SERIAL1 once the adapter is on SERIAL0
        with GroundStation(sitl.gcs_url, "copter") as gcs:
            gcs.stream("GLOBAL_POSITION_INT", 10)
            gcs.wait(lambda s: s.north_max > 15 and s.alt > 8, 300, "the first leg")
            gcs.set_mode("LOITER")
            report = finish_cli(proc)
            seen = next(t for t, m in gcs.seen.modes if m == "LOITER")
    finally:
        sitl.stop()
    [end] = [r["end"] for r in report["records"] if r["status"] == "FAILED"]
    return {"heartbeat_to_finish_ms": (end - seen) * 1000}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--speedups", default="1,5,10")
    parser.add_argument("--round-trips", type=int, default=200)
    args = parser.parse_args()
    reason = missing(sitl_dir(), ("copter",))
    if reason is not None:
        print(f"bench_sitl: no ArduPilot SITL configured, nothing measured ({reason})")
        return 0
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="bench_sitl_") as tmp:
        workdir = Path(tmp)
        out["survey"] = {}
        for s in filter(None, args.speedups.split(",")):
            out["survey"][f"x{float(s):g}"] = row = survey(float(s), workdir)
            print(f"survey x{float(s):g}: {json.dumps(row)}", file=sys.stderr, flush=True)
        out["round_trip"] = round_trips(args.round_trips, workdir)
        out["fault"] = fault_latency(workdir)
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    for key, row in out["survey"].items():
        print(
            f"survey {key}: wall {row['wall_s']:.1f} s, mission {row['mission_s']:.1f} s, "
            f"makespan planned {row['planned_makespan_s']:.1f} s / flown "
            f"{row['flown_makespan_s']:.1f} s wall ({row['flown_makespan_sim_s']:.1f} s "
            f"simulated), armable after {row['time_to_armable_s']:.1f} s wall "
            f"({row['time_to_armable_sim_s']:.1f} s simulated)"
        )
    rt = out["round_trip"]
    print(
        f"command round trip: adapter {rt['adapter_median_ms']:.2f} ms median "
        f"(p99 {rt['adapter_p99_ms']:.2f}), raw pymavlink {rt['pymavlink_median_ms']:.2f} ms "
        f"(p99 {rt['pymavlink_p99_ms']:.2f}), ratio {rt['ratio_median']:.2f}"
    )
    print(f"takeover -> FINISH(failure): {out['fault']['heartbeat_to_finish_ms']:.0f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
