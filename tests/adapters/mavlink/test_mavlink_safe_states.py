"""The vehicle's safe mode on every way an action or a mission can end early.

``safe_mode`` (copter LAND by default, or RTL / BRAKE ...; rover HOLD) is applied on
a cancel from the executor, on a failed action, when the mission aborts, when the
link comes back after it was lost mid-action, and when ``plansys-bridge run`` is
stopped by SIGINT or SIGTERM (a real signal to a real child process flying the
vehicle double over TCP, and flying ArduPilot SITL where ``PLANSYS_BRIDGE_SITL_DIR``
names it).
"""

from __future__ import annotations

import asyncio
import signal
import subprocess
import threading
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from mavlink_support import CONFIGS, SPEEDUP, build, make_hub, performer_config
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from sitl_support import GroundStation, Sitl, cli, sitl_mission, start_cli
from test_mavlink_missions import fast, load, run

from plansys_bridge.hub.auction import ActionClient, AuctionPolicy
from plansys_bridge.hub.hub import Hub

POLICY = AuctionPolicy(retry_period=0.2, give_up_after=5.0, liveness_timeout=3.0)


async def _airborne(hub: Hub, double: VehicleDouble) -> None:
    client = ActionClient(hub, "takeoff", ("uav1", "pad"), policy=POLICY)
    assert (await client.run()).success


def _with_performer(double: VehicleDouble, body: Any, **extra: Any) -> None:
    async def main() -> None:
        hub = make_hub()
        await hub.start()
        performer = build(performer_config("uav1", double.url, "copter", **extra), hub)
        try:
            await performer.start()
            await asyncio.wait_for(body(hub), 40)
        finally:
            await performer.stop()
            await hub.close()

    asyncio.run(main())


@pytest.mark.parametrize("mode", ["LAND", "RTL", "BRAKE"])
def test_cancel_puts_the_copter_in_its_safe_mode(mode: str) -> None:
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=2.0, cruise_speed=2.0) as double:

        async def body(hub: Hub) -> None:
            await _airborne(hub, double)
            client = ActionClient(hub, "fly", ("uav1", "pad", "north_field"), policy=POLICY)
            task = asyncio.ensure_future(client.run())
            while double.state()["north"] < 3:
                await asyncio.sleep(0.01)
            client.cancel()
            assert (await task).cancelled

        _with_performer(double, body, safe_mode=mode)
        assert double.wait_for(lambda s: s["mode"] == mode, timeout=5), double.state()


def test_lost_link_makes_the_copter_safe_once_it_is_heard_again() -> None:
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=2.0, cruise_speed=2.0) as double:
        outcome: list[Any] = []

        async def body(hub: Hub) -> None:
            await _airborne(hub, double)
            client = ActionClient(hub, "fly", ("uav1", "pad", "north_field"), policy=POLICY)
            task = asyncio.ensure_future(client.run())
            while double.state()["north"] < 3:
                await asyncio.sleep(0.01)
            double.drop_link(3.0 * SPEEDUP)  # 3 s of wall time: the heartbeat limit is 1 s
            outcome.append(await task)
            assert double.state()["mode"] == "GUIDED"  # nothing got through meanwhile
            while double.state()["mode"] != "LAND":
                await asyncio.sleep(0.05)

        _with_performer(double, body)  # the default safe mode: LAND
        assert not outcome[0].success and "no HEARTBEAT" in outcome[0].status
        assert double.state()["mode"] == "LAND"


def _mission(double: VehicleDouble, tmp_path: Path, safe_mode: str | None) -> Path:
    data = yaml.safe_load((CONFIGS / "mavlink_copter.yaml").read_text())
    for key in ("domain", "problem"):
        data[key] = str(CONFIGS / data[key])
    entry = data["performers"][0]
    del entry["double"]
    entry.update(
        url=double.url,
        locations=str(CONFIGS / entry["locations"]),
        timeouts={"heartbeat": 2.0, "command": 1.0, "ekf": 60, "arm": 30, "action": 120},
    )
    entry.pop("safe_mode", None)  # None: the default
    if safe_mode is not None:
        entry["safe_mode"] = safe_mode
    path = tmp_path / "mission.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.mark.parametrize(
    ("sig", "code", "mode"),
    [(signal.SIGTERM, 143, "LAND"), (signal.SIGINT, 130, "RTL")],
    ids=["SIGTERM-LAND", "SIGINT-RTL"],
)
def test_a_signal_to_run_leaves_the_copter_in_its_safe_mode(
    tmp_path: Path, sig: signal.Signals, code: int, mode: str
) -> None:
    # slow enough that the signal arrives mid-flight: 5x, cruising at 2 m/s
    with VehicleDouble("copter", speedup=5, ekf_delay=2.0, cruise_speed=2.0) as double:
        proc = subprocess.Popen(
            [*cli(), "run", str(_mission(double, tmp_path, mode))],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
            text=True,
        )
        try:
            flying = double.wait_for(lambda s: s["alt"] > 5 and s["north"] > 2, timeout=90)
            state = double.state()
            proc.send_signal(sig)
            out, err = proc.communicate(timeout=30)
            err += out
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        assert flying, f"never flying: {double.state()}\n{err}"
        assert state["mode"] == "GUIDED"
        assert proc.returncode == code, err
        assert ("terminated" if sig == signal.SIGTERM else "interrupted") in err
        assert "Traceback" not in err
        # the process is gone; the vehicle carries on in its safe mode
        assert double.state()["mode"] == mode, double.state()


@pytest.mark.sitl
@pytest.mark.parametrize(
    ("sig", "code", "mode"),
    [(signal.SIGTERM, 143, "LAND"), (signal.SIGINT, 130, "RTL"), (signal.SIGTERM, 143, "BRAKE")],
    ids=["SIGTERM-LAND", "SIGINT-RTL", "SIGTERM-BRAKE"],
)
def test_a_signal_to_run_leaves_sitl_in_its_safe_mode(
    sitl: Sitl, tmp_path: Path, sig: signal.Signals, code: int, mode: str
) -> None:
    copter = sitl.start("copter", speedup=10.0)

    def safe(data: dict[str, Any]) -> None:
        data["performers"][0]["safe_mode"] = mode

    mission = sitl_mission("mavlink_copter.yaml", {"uav1": copter.url}, tmp_path, change=safe)
    proc = start_cli(mission)  # SITL opens its other ports once the adapter connects
    try:
        with GroundStation(copter.gcs_url, "copter") as gcs:
            gcs.stream("GLOBAL_POSITION_INT", 10)
            gcs.wait(lambda s: s.north_max > 10 and s.alt > 8, 180, "10 m into the first leg")
            assert gcs.seen.modes[-1][1] == "GUIDED"
            proc.send_signal(sig)
            _out, err = proc.communicate(timeout=60)
            assert proc.returncode == code, err + _out
            gcs.wait(lambda s: s.modes[-1][1] == mode, 20, f"mode {mode}")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def test_an_aborted_mission_leaves_the_copter_in_its_safe_mode() -> None:
    # a low battery halts the flight; with no replan allowed the mission aborts
    with VehicleDouble("copter", speedup=SPEEDUP, ekf_delay=4.0, cruise_speed=2.0) as double:
        data = fast(load("mavlink_copter.yaml"))
        entry = data["performers"][0]
        del entry["double"]
        entry.update(url=double.url, safe_mode="RTL")
        data["replanning"] = {"max_replans": 0}
        injector = threading.Thread(
            target=lambda: (
                double.wait_for(lambda s: s["north"] > 10, 30) and double.set_battery(15.0)
            ),
            name="low-battery",
        )
        injector.start()
        try:
            report = run(data)
        finally:
            injector.join()
        assert not report.success, report.summary()
        assert double.wait_for(lambda s: s["mode"] == "RTL", timeout=5), double.state()


def test_a_repeated_sigterm_does_not_cut_the_safe_stop_short(tmp_path: Path) -> None:
    # supervisors and scripts may send SIGTERM more than once; SIGKILL is the way to force
    with VehicleDouble("copter", speedup=5, ekf_delay=2.0, cruise_speed=2.0) as double:
        proc = subprocess.Popen(
            [*cli(), "run", str(_mission(double, tmp_path, None))],  # default: LAND
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
            text=True,
        )
        try:
            assert double.wait_for(lambda s: s["alt"] > 5 and s["north"] > 2, timeout=90)
            for _ in range(3):
                proc.send_signal(signal.SIGTERM)
                time.sleep(0.02)
            _out, err = proc.communicate(timeout=30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        assert proc.returncode == 143, err
        assert "Traceback" not in err
        assert double.state()["mode"] == "LAND", double.state()
