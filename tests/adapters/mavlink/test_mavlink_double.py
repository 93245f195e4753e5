"""The vehicle double behaves like ArduPilot SITL where a ground station can tell."""

from __future__ import annotations

import math
import socket
import subprocess
import sys
import time
from typing import Any

import pytest
from mavlink_support import free_port
from plansys_bridge_adapters.mavlink.double import SimParams, VehicleDouble, VehicleSim
from plansys_bridge_adapters.mavlink.geo import GeoPoint, offset
from plansys_bridge_adapters.mavlink.modes import mode_number
from pymavlink.dialects.v20 import ardupilotmega as ml


class RawClient:
    """A bare TCP MAVLink client: what a GCS sees, with no client-side cleverness."""

    def __init__(self, url: str) -> None:
        _, host, port = url.split(":")
        self.sock = socket.create_connection((host, int(port)), timeout=2)
        self.sock.settimeout(0.05)
        self.mav = ml.MAVLink(self, srcSystem=255, srcComponent=190)
        self.parser = ml.MAVLink(None)
        self.seen: list[Any] = []

    def write(self, data: bytes) -> None:
        self.sock.sendall(data)

    def pump(self, seconds: float) -> list[Any]:
        end = time.monotonic() + seconds
        got: list[Any] = []
        while time.monotonic() < end:
            try:
                data = self.sock.recv(65535)
            except TimeoutError:
                continue
            got.extend(self.parser.parse_buffer(data) or [])
        self.seen.extend(got)
        return got

    def until(self, predicate: Any, seconds: float = 3.0) -> Any:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            for msg in self.pump(0.02):
                if predicate(msg):
                    return msg
        raise AssertionError("expected message never came")

    def command(self, cmd: int, *params: float) -> int:
        p = list(params) + [0.0] * (7 - len(params))
        self.mav.command_long_send(1, 1, cmd, 0, *p)
        ack = self.until(lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd)
        return int(ack.result)

    def close(self) -> None:
        self.sock.close()


def test_time_starts_only_when_a_client_connects() -> None:
    with VehicleDouble("copter", speedup=50) as double:
        time.sleep(0.1)
        assert double.state()["time"] == 0.0
        client = RawClient(double.url)
        try:
            hb = client.until(lambda m: m.get_type() == "HEARTBEAT")
            assert (hb.type, hb.autopilot) == (2, 3)
            assert double.state()["time"] > 0.0
        finally:
            client.close()


def test_rover_heartbeat_and_modes() -> None:
    with VehicleDouble("rover", speedup=50) as double:
        client = RawClient(double.url)
        try:
            hb = client.until(lambda m: m.get_type() == "HEARTBEAT")
            assert hb.type == 10
            # after RC input has put the rover in MANUAL (2.8 s), a mode sticks
            assert double.wait_for(lambda s: s["time"] > 3.0, 5)
            assert client.command(ml.MAV_CMD_DO_SET_MODE, 1, 15) == ml.MAV_RESULT_ACCEPTED
            client.until(lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 15)
            # 9 is LAND on a copter but CIRCLE on a rover; 14 (FLIP) is no rover mode
            assert client.command(ml.MAV_CMD_DO_SET_MODE, 1, 14) == ml.MAV_RESULT_UNSUPPORTED
        finally:
            client.close()


def test_telemetry_only_when_requested() -> None:
    with VehicleDouble("copter", speedup=50) as double:
        client = RawClient(double.url)
        try:
            kinds = {m.get_type() for m in client.pump(0.3)}
            assert "HEARTBEAT" in kinds
            assert not kinds & {"GLOBAL_POSITION_INT", "SYS_STATUS", "EKF_STATUS_REPORT"}
            assert (
                client.command(
                    ml.MAV_CMD_SET_MESSAGE_INTERVAL, ml.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 100_000
                )
                == ml.MAV_RESULT_ACCEPTED
            )
            kinds = {m.get_type() for m in client.pump(0.3)}
            assert "GLOBAL_POSITION_INT" in kinds
            assert "SYS_STATUS" not in kinds
            assert (
                client.command(
                    ml.MAV_CMD_SET_MESSAGE_INTERVAL, ml.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, -1
                )
                == ml.MAV_RESULT_ACCEPTED
            )
            client.pump(0.05)
            assert "GLOBAL_POSITION_INT" not in {m.get_type() for m in client.pump(0.3)}
        finally:
            client.close()


def test_arming_refused_until_ekf_then_auto_disarm() -> None:
    with VehicleDouble("copter", speedup=50, ekf_delay=20.0) as double:
        client = RawClient(double.url)
        try:
            assert (
                client.command(
                    ml.MAV_CMD_SET_MESSAGE_INTERVAL, ml.MAVLINK_MSG_ID_EKF_STATUS_REPORT, 200_000
                )
                == 0
            )
            client.until(lambda m: m.get_type() == "HEARTBEAT")
            assert client.command(ml.MAV_CMD_DO_SET_MODE, 1, mode_number("copter", "GUIDED")) == 0
            assert client.command(ml.MAV_CMD_COMPONENT_ARM_DISARM, 1) == ml.MAV_RESULT_FAILED
            texts = [m.text for m in client.seen if m.get_type() == "STATUSTEXT"]
            assert "Arm: Need Position Estimate" in texts
            ekf = client.until(
                lambda m: m.get_type() == "EKF_STATUS_REPORT" and m.flags & ml.EKF_POS_HORIZ_ABS,
                seconds=3,
            )
            assert not ekf.flags & ml.EKF_CONST_POS_MODE
            assert client.command(ml.MAV_CMD_COMPONENT_ARM_DISARM, 1) == ml.MAV_RESULT_ACCEPTED
            client.until(
                lambda m: (
                    m.get_type() == "HEARTBEAT" and m.base_mode & ml.MAV_MODE_FLAG_SAFETY_ARMED
                )
            )
            # idle on the ground: DISARM_DELAY (10 s simulated) later it disarms itself
            client.until(
                lambda m: (
                    m.get_type() == "HEARTBEAT" and not m.base_mode & ml.MAV_MODE_FLAG_SAFETY_ARMED
                ),
                seconds=3,
            )
            assert double.state()["time"] >= 30.0
        finally:
            client.close()


def test_takeoff_needs_arming_and_guided() -> None:
    sim = VehicleSim(SimParams(model="copter", ekf_delay=0.5))
    sim.connect()
    sim.step(1.0)
    sim._command(ml.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, 10.0))
    assert sim.landed and not sim.armed
    sim._command(ml.MAV_CMD_DO_SET_MODE, (1, mode_number("copter", "GUIDED"), 0, 0, 0, 0, 0))
    sim._command(ml.MAV_CMD_COMPONENT_ARM_DISARM, (1, 0, 0, 0, 0, 0, 0))
    sim._command(ml.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, 10.0))
    for _ in range(200):
        sim.step(0.05)
    assert sim.alt == pytest.approx(10.0)
    sim.inject_failsafe("Radio")
    assert sim.mode_name == "RTL"
    for _ in range(2000):
        sim.step(0.05)
    assert sim.landed and not sim.armed


def test_battery_drains_and_its_failsafe_fires() -> None:
    sim = VehicleSim(
        SimParams(model="rover", ekf_delay=0.5, battery_capacity_s=100.0, battery_failsafe_pct=50.0)
    )
    sim.connect()
    sim.step(1.0)
    sim._command(ml.MAV_CMD_DO_SET_MODE, (1, 15, 0, 0, 0, 0, 0))
    sim._command(ml.MAV_CMD_COMPONENT_ARM_DISARM, (1, 0, 0, 0, 0, 0, 0))
    far = offset(sim.p.home, 10_000, 0)
    sim.guided_target = GeoPoint(far.lat, far.lon, 0.0)
    for _ in range(2000):
        sim.step(0.05)
        if sim.failsafe:
            break
    assert sim.failsafe and sim.mode_name == "HOLD"
    assert 49.0 <= sim.battery <= 50.0
    parser = ml.MAVLink(None)
    texts = [
        m.text
        for m in parser.parse_buffer(b"".join(sim.take_output())) or []
        if m.get_type() == "STATUSTEXT"
    ]
    assert "Battery Failsafe" in texts


def test_command_line_serves_a_vehicle() -> None:
    port = free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "plansys_bridge_adapters.mavlink.double",
            "--model",
            "rover",
            "--port",
            str(port),
            "--speedup",
            "10",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert f"tcp:127.0.0.1:{port}" in line
        client = RawClient(f"tcp:127.0.0.1:{port}")
        try:
            assert client.until(lambda m: m.get_type() == "HEARTBEAT").type == 10
        finally:
            client.close()
    finally:
        proc.terminate()
        assert proc.wait(timeout=5) == 0
        if proc.stdout is not None:
            proc.stdout.close()


def test_bad_double_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="model"):
        VehicleDouble("plane")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="speedup"):
        VehicleDouble("copter", speedup=0)


def test_non_numbers_in_commands_are_refused_not_fatal() -> None:
    """NaN/infinite parameters and impossible coordinates are refused, as ArduPilot does;
    the double keeps serving (they used to end its thread with ValueError)."""
    nan, inf = float("nan"), float("inf")
    with VehicleDouble("copter", speedup=50, ekf_delay=0.0) as double:
        client = RawClient(double.url)
        try:
            client.until(lambda m: m.get_type() == "HEARTBEAT")
            denied = ml.MAV_RESULT_DENIED
            assert client.command(ml.MAV_CMD_DO_SET_MODE, 1, inf) == denied
            assert client.command(ml.MAV_CMD_COMPONENT_ARM_DISARM, 1, nan) == denied
            assert client.command(ml.MAV_CMD_SET_MESSAGE_INTERVAL, nan, 1e5) == denied
            guided = mode_number("copter", "GUIDED")
            assert client.command(ml.MAV_CMD_DO_SET_MODE, 1, guided) == ml.MAV_RESULT_ACCEPTED
            assert client.command(ml.MAV_CMD_COMPONENT_ARM_DISARM, 1) == ml.MAV_RESULT_ACCEPTED
            failed = ml.MAV_RESULT_FAILED
            assert client.command(ml.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, nan, 0, 0, nan) == failed
            assert client.command(ml.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, nan, 0, 0, 5) == 0
            assert client.command(ml.MAV_CMD_DO_REPOSITION, -1, 0, 0, nan, 95, 0, 5) == denied
            assert client.command(ml.MAV_CMD_DO_REPOSITION, -1, 0, 0, nan, nan, 0, 5) == denied
            client.mav.set_position_target_global_int_send(
                0, 1, 1, 6, 0x0DF8, 2**31 - 1, 0, 5.0, 0, 0, 0, 0, 0, 0, 0, 0
            )
            client.mav.set_position_target_global_int_send(
                0, 1, 1, 6, 0x0DF8, 0, 0, nan, 0, 0, 0, 0, 0, 0, 0, 0
            )
            client.pump(0.1)
            state = double.state()
            assert all(math.isfinite(state[k]) for k in ("alt", "north", "east"))
            target = double.sim.guided_target
            assert target is None or abs(target.lat) <= 90
            # still alive: it answers and its heartbeat goes on
            assert client.command(ml.MAV_CMD_DO_SET_MODE, 1, guided) == ml.MAV_RESULT_ACCEPTED
            client.pump(0.05)
            client.until(lambda m: m.get_type() == "HEARTBEAT")
        finally:
            client.close()
