"""Helpers for the tests against real ArduPilot SITL (imported as ``sitl_support``).

* :class:`Sitl`: the instances one test started (the ``sitl`` fixture);
* :class:`GroundStation`: a second ground station (pymavlink) on another SITL port:
  watches HEARTBEAT, position and STATUSTEXT, reads and sets parameters, changes
  the mode, as Mission Planner or MAVProxy would next to the adapter;
* :class:`Relay`: a TCP link between the adapter and SITL that a test can cut;
* :func:`sitl_mission`: a shipped mission file with its vehicles pointed at SITL;
* :func:`run_cli`: ``plansys-bridge run MISSION --json`` in a child process;
* :class:`RealTimeFleet`: the fleet mission at speedup 1, flying in the background.
"""

from __future__ import annotations

import contextlib
import json
import select
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import yaml
from mavlink_support import CONFIGS
from plansys_bridge_adapters.mavlink.errors import LinkError
from plansys_bridge_adapters.mavlink.geo import GeoPoint, distance_3d_m
from plansys_bridge_adapters.mavlink.headway import Headway
from plansys_bridge_adapters.mavlink.modes import Model, mode_name, mode_number, model_of_type
from plansys_bridge_adapters.mavlink.sitl import (
    DEFAULT_HOME,
    SitlProcess,
    instance_free,
    missing,
    sitl_dir,
)
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as ml

SITL_TIMEOUTS = {"connect": 60, "heartbeat": 5, "command": 2, "ekf": 240, "arm": 60, "action": 300}
"""Wall-clock limits for SITL runs (the EKF takes ~42 simulated seconds)."""
ROVER_HOME = GeoPoint(DEFAULT_HOME.lat, 149.165600, DEFAULT_HOME.alt)
"""The fleet's rover starts 34 m east of the copter (the configs' double homes)."""
GCS_SYSID = 250
"""The second ground station's system id: not the adapter's 255, so ArduPilot keeps
their links apart and its GCS failsafe keeps watching the adapter's heartbeat."""


@dataclass
class Seen:
    """What the ground station heard, with wall-clock stamps (``time.time()``)."""

    modes: list[tuple[float, str]] = field(default_factory=list)
    """Each mode change (and the first HEARTBEAT's mode)."""
    armed: list[tuple[float, bool]] = field(default_factory=list)
    texts: list[tuple[float, int, str]] = field(default_factory=list)
    max_alt: float = 0.0
    alt: float = 0.0
    north_max: float = 0.0
    params: dict[str, float] = field(default_factory=dict)
    position: tuple[float, float] | None = None
    counts: dict[str, int] = field(default_factory=dict)
    """Messages heard, by type."""
    track: list[tuple[float, float, GeoPoint]] = field(default_factory=list)
    """Each GLOBAL_POSITION_INT: wall stamp, the vehicle's own time (s), position."""


class GroundStation:
    """A pymavlink ground station on one SITL port, read by a background thread."""

    def __init__(self, url: str, model: Model | None = None) -> None:
        self.url = url
        self.model = model
        self.seen = Seen()
        self.conn: Any = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.home: tuple[float, float] | None = None

    def __enter__(self) -> GroundStation:
        deadline = time.monotonic() + 30
        while True:
            try:
                conn = mavutil.mavlink_connection(
                    self.url, source_system=GCS_SYSID, source_component=190, retries=0
                )
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        conn.mav = ml.MAVLink(conn, srcSystem=GCS_SYSID, srcComponent=190)
        conn.mav.robust_parsing = True
        self.conn = conn
        self._thread = threading.Thread(target=self._read, name="sitl-gcs", daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(5)
        with contextlib.suppress(Exception):
            self.conn.close()

    # --------------------------------------------------------------- reading
    def _read(self) -> None:
        last_hb = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            if now - last_hb > 1.0:
                last_hb = now
                with contextlib.suppress(OSError):
                    self.conn.mav.heartbeat_send(6, 8, 0, 0, ml.MAV_STATE_ACTIVE)
            try:
                msg = self.conn.recv_match(blocking=True, timeout=0.1)
            except (OSError, ValueError):
                return
            if msg is not None and msg.get_srcSystem() != GCS_SYSID:
                with self._lock:
                    self._on(msg)

    def _on(self, msg: Any) -> None:
        kind, stamp, seen = msg.get_type(), time.time(), self.seen
        seen.counts[kind] = seen.counts.get(kind, 0) + 1
        if kind == "HEARTBEAT" and msg.get_srcComponent() == 1 and msg.type not in (6, 27):
            self.model = self.model or model_of_type(msg.type)
            name = mode_name(self.model or "copter", msg.custom_mode)
            if not seen.modes or seen.modes[-1][1] != name:
                seen.modes.append((stamp, name))
            armed = bool(msg.base_mode & ml.MAV_MODE_FLAG_SAFETY_ARMED)
            if not seen.armed or seen.armed[-1][1] != armed:
                seen.armed.append((stamp, armed))
        elif kind == "GLOBAL_POSITION_INT":
            seen.alt = msg.relative_alt / 1000
            point = GeoPoint(msg.lat / 1e7, msg.lon / 1e7, seen.alt)
            seen.track.append((stamp, msg.time_boot_ms / 1000, point))
            seen.max_alt = max(seen.max_alt, seen.alt)
            seen.position = (msg.lat / 1e7, msg.lon / 1e7)
            if self.home is None and msg.lat != 0:  # 0, 0 until the EKF has an origin
                self.home = seen.position
            if self.home is None:
                return
            seen.north_max = max(seen.north_max, (seen.position[0] - self.home[0]) * 111_195)
        elif kind == "STATUSTEXT":
            seen.texts.append((stamp, msg.severity, msg.text))
        elif kind == "PARAM_VALUE":
            seen.params[msg.param_id] = float(msg.param_value)

    def wait(self, predicate: Callable[[Seen], bool], timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self._lock:
                if predicate(self.seen):
                    return
            time.sleep(0.02)
        raise AssertionError(f"{self.url}: timed out after {timeout:g} s waiting for {what}")

    @property
    def mode(self) -> str:
        with self._lock:
            return self.seen.modes[-1][1] if self.seen.modes else "UNKNOWN"

    @property
    def armed(self) -> bool:
        with self._lock:
            return bool(self.seen.armed and self.seen.armed[-1][1])

    def stalled_at(self, target: GeoPoint, window: float, since: float) -> float | None:
        """Wall time of the first position heard after ``since`` that showed the vehicle
        no closer to ``target`` for ``window`` seconds of its own time (None: never)."""
        headway = Headway(window)
        with self._lock:
            track = [entry for entry in self.seen.track if entry[0] >= since]
        for stamp, vehicle_time, point in track:
            if not headway.update(distance_3d_m(point, target), vehicle_time):
                return stamp
        return None

    def text_time(self, fragment: str) -> float | None:
        """Wall time of the first STATUSTEXT containing ``fragment`` (case-insensitive)."""
        with self._lock:
            for stamp, _, text in self.seen.texts:
                if fragment.lower() in text.lower():
                    return stamp
        return None

    # --------------------------------------------------------------- talking
    def stream(self, message: str, hz: float, timeout: float = 10.0) -> None:
        """Ask for ``message`` on this ground station's own link, again until it comes
        (a request sent while SITL is still opening the port is lost)."""
        msg_id = getattr(ml, f"MAVLINK_MSG_ID_{message}")
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self._lock:
                wanted = self.seen.counts.get(message, 0) + 2
            self._command(ml.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / hz)
            with contextlib.suppress(AssertionError):
                self.wait(partial(_heard, message, wanted), 1.0, message)
                return
        raise AssertionError(f"{self.url}: no {message} within {timeout:g} s of asking")

    def _command(self, command: int, *params: float) -> None:
        p = [float(x) for x in params] + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(1, 1, command, 0, *p)

    def set_mode(self, name: str) -> None:
        """MAV_CMD_DO_SET_MODE from this ground station (a takeover)."""
        number = mode_number(self.model or "copter", name)
        self._command(ml.MAV_CMD_DO_SET_MODE, ml.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, number)

    def param(self, name: str, timeout: float = 10.0) -> float:
        """Read one parameter (PARAM_REQUEST_READ), retrying until PARAM_VALUE comes."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.conn.mav.param_request_read_send(1, 1, name.encode(), -1)
            end = min(deadline, time.monotonic() + 1.0)
            while time.monotonic() < end:
                with self._lock:
                    if name in self.seen.params:
                        return self.seen.params.pop(name)
                time.sleep(0.02)
        raise AssertionError(f"{self.url}: no PARAM_VALUE for {name} within {timeout:g} s")

    def set_param(self, name: str, value: float, timeout: float = 10.0) -> None:
        """PARAM_SET until the vehicle echoes the new value."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self._lock:
                self.seen.params.pop(name, None)
            self.conn.mav.param_set_send(1, 1, name.encode(), value, ml.MAV_PARAM_TYPE_REAL32)
            end = min(deadline, time.monotonic() + 1.0)
            while time.monotonic() < end:
                with self._lock:
                    got = self.seen.params.get(name)
                if got is not None and abs(got - value) < 1e-3:
                    return
                time.sleep(0.02)
        raise AssertionError(f"{self.url}: {name} not set to {value} within {timeout:g} s")


def _heard(message: str, count: int, seen: Seen) -> bool:
    return seen.counts.get(message, 0) >= count


class Sitl:
    """Starts ArduPilot SITL instances for one test and stops them (by pid) after it."""

    def __init__(self, folder: Path, workdir: Path) -> None:
        self.folder = folder
        self.workdir = workdir
        self.running: list[SitlProcess] = []

    def start(
        self,
        model: Model,
        *,
        instance: int | None = None,
        speedup: float = 10.0,
        home: GeoPoint = DEFAULT_HOME,
        params: Mapping[str, float] | None = None,
    ) -> SitlProcess:
        """A fresh instance (own working directory, wiped eeprom) listening on its port.

        ``instance=None`` takes the lowest instance number whose ports are free, so
        tests can run next to another SITL on the machine.
        """
        if instance is None:
            taken = {s.instance for s in self.running}
            instance = next(n for n in range(1, 60) if n not in taken and instance_free(n))
        sitl = SitlProcess(
            model,
            instance,
            self.workdir / f"{model}{instance}",
            speedup=speedup,
            home=home,
            params=params,
            folder=self.folder,
        )
        self.running.append(sitl)
        return sitl.start()

    def stop_all(self) -> None:
        for sitl in self.running:
            sitl.stop()


class Relay:
    """A TCP relay between the adapter and SITL: :meth:`cut` drops the link at once,
    as a radio going out of range or a cable pulled would."""

    def __init__(self, target_url: str) -> None:
        _, host, port = target_url.split(":")
        self._target = (host, int(port))
        self._server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._server.bind(("127.0.0.1", 0))
        self._server.listen(1)
        self.url = f"tcp:127.0.0.1:{self._server.getsockname()[1]}"
        self._sockets: list[socket.socket] = [self._server]
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._run, name="sitl-relay", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            client, _ = self._server.accept()
            upstream = socket.create_connection(self._target)
        except OSError:
            return
        self._sockets += [client, upstream]
        peers = {client: upstream, upstream: client}
        while not self._closed.is_set():
            try:
                ready, _, _ = select.select(list(peers), [], [], 0.1)
                for sock in ready:
                    data = sock.recv(65536)
                    if not data:
                        return
                    peers[sock].sendall(data)
            except (OSError, ValueError):
                return

    def cut(self) -> None:
        """Close both sides: the adapter sees its link closed, SITL its client gone."""
        self._closed.set()
        for sock in self._sockets:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                sock.close()

    def close(self) -> None:
        self.cut()
        self._thread.join(5)


# ------------------------------------------------------------------ missions
def sitl_mission(
    name: str,
    urls: Mapping[str, str],
    workdir: Path,
    *,
    replans: int = 0,
    change: Callable[[dict[str, Any]], None] | None = None,
) -> Path:
    """The shipped mission ``name`` with each performer (by vehicle) on its SITL url."""
    data = yaml.safe_load((CONFIGS / name).read_text())
    for key in ("domain", "problem"):
        data[key] = str(CONFIGS / data[key])
    for entry in data["performers"]:
        entry.pop("double", None)
        entry["url"] = urls[entry["vehicle"]]
        entry["timeouts"] = SITL_TIMEOUTS
        if isinstance(entry.get("locations"), str):
            entry["locations"] = str(CONFIGS / entry["locations"])
    data["replanning"] = {"max_replans": replans}
    data["timeout"] = 600
    if change is not None:
        change(data)
    path = workdir / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def cli() -> list[str]:
    """The ``plansys-bridge`` command of this environment."""
    script = Path(sys.executable).with_name("plansys-bridge")
    return [str(script)] if script.exists() else [sys.executable, "-m", "plansys_bridge"]


def start_cli(mission: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [*cli(), "run", str(mission), "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )


def finish_cli(proc: subprocess.Popen[str], timeout: float = 300) -> dict[str, Any]:
    """Wait for ``plansys-bridge run`` and return its JSON report (with stderr kept)."""
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.terminate()
        out, err = proc.communicate(timeout=10)
        raise AssertionError(
            f"plansys-bridge run still running after {timeout:g} s:\n{err}"
        ) from None
    try:
        report: dict[str, Any] = json.loads(out)
    except json.JSONDecodeError:
        raise AssertionError(f"exit {proc.returncode}, no JSON report:\n{out}\n{err}") from None
    report["exit_code"] = proc.returncode
    report["stderr"] = err
    return report


def run_cli(mission: Path, timeout: float = 300) -> dict[str, Any]:
    return finish_cli(start_cli(mission), timeout)


def describe(report: Mapping[str, Any]) -> str:
    """The report's actions one per line, for assertion messages."""
    lines = [f"{report.get('status')}: {report.get('message')}"]
    for r in report.get("records", []):
        lines.append(f"  {r['status']:<10} {r['action']} by {r['performer']}: {r['message']}")
    lines.append(str(report.get("stderr", ""))[-2000:])
    return "\n".join(lines)


def assert_succeeded(report: Mapping[str, Any]) -> None:
    """SUCCEEDED with every action succeeded: none failed or halted on the way."""
    assert report["success"] and report["exit_code"] == 0, describe(report)
    assert report["records"], describe(report)
    assert all(r["status"] == "SUCCEEDED" for r in report["records"]), describe(report)
    assert report["replans"] == 0, describe(report)


# ------------------------------------------------------------ real-time fleet
@dataclass
class RealTimeFleet:
    """The fleet mission with copter and rover at speedup 1, started early and checked
    late: in real time the mission mostly waits (42 s until the EKF uses GPS, then the
    flights at their real speeds, about two minutes in all), so other tests run
    meanwhile instead of the suite waiting for it."""

    copter: SitlProcess | None = None
    rover: SitlProcess | None = None
    proc: subprocess.Popen[str] | None = None
    skipped: str | None = None
    """Why the fleet was not started: no SITL."""
    error: Exception | None = None
    """What went wrong starting it: raised by :meth:`started` in the check, not in
    whichever test happened to start it."""
    launcher: Sitl | None = None

    @classmethod
    def start(cls, workdir: Path) -> RealTimeFleet:
        folder = sitl_dir()
        reason = missing(folder)
        if reason is not None:
            return cls(skipped=reason)
        assert folder is not None
        fleet = cls(launcher=Sitl(folder, workdir))
        try:
            assert fleet.launcher is not None
            fleet.copter = fleet.launcher.start("copter", speedup=1.0)
            fleet.rover = fleet.launcher.start("rover", speedup=1.0, home=ROVER_HOME)
            urls = {"uav1": fleet.copter.url, "ugv1": fleet.rover.url}
            fleet.proc = start_cli(sitl_mission("mavlink_fleet.yaml", urls, workdir))
        except (LinkError, OSError) as exc:
            fleet.error = exc
            fleet.close()
            return fleet
        fleet._wait_connected(timeout=30.0)
        return fleet

    def _wait_connected(self, timeout: float) -> None:
        """Until the adapter has connected to both vehicles (SITL logs it), or the
        mission ended: the mission's start-up, a burst of work for the machine, is then
        over before the next test starts its own vehicle. A mission slower than that
        is left to the check."""
        deadline = time.monotonic() + timeout
        for vehicle in (self.copter, self.rover):
            assert vehicle is not None and self.proc is not None
            said = f"Connection on serial port {vehicle.port}"
            while said not in _read_log(vehicle.log_path) and self.proc.poll() is None:
                if time.monotonic() > deadline:
                    return
                time.sleep(0.1)

    def started(self) -> tuple[SitlProcess, SitlProcess, subprocess.Popen[str]]:
        """The running fleet; raises what went wrong starting it."""
        if self.error is not None:
            raise AssertionError(f"the real-time fleet did not start: {self.error!r}")
        assert self.copter is not None and self.rover is not None and self.proc is not None
        return self.copter, self.rover, self.proc

    def close(self) -> None:
        """Stop the mission (if still running) and both SITL instances."""
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()
        if self.launcher is not None:
            self.launcher.stop_all()


def _read_log(path: Path) -> str:
    try:
        return path.read_text(errors="replace")
    except OSError:
        return ""
