"""Start and stop ArduPilot SITL binaries (``arducopter``, ``ardurover``) on loopback.

ArduPilot ships no SITL in any package registry; users build it from ArduPilot's
source and keep the binaries and the default parameter files (``copter.parm``,
``rover.parm`` from ``Tools/autotest/default_params``) in one folder. Tests and
benchmarks find that folder through ``PLANSYS_BRIDGE_SITL_DIR``.

Each :class:`SitlProcess` runs one instance the way ``sim_vehicle.py`` starts it
(synthetic clock, ``--model``, ``--speedup``, ``--defaults``, ``-I N``), in its own
working directory (eeprom.bin, logs) with the eeprom wiped. Instance ``N`` serves
MAVLink on TCP ``5760+10N`` (the first client starts the simulated clock) and on
``5762+10N`` / ``5763+10N`` for more ground stations. SITL listens on all
interfaces; clients here always connect to 127.0.0.1.
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from .errors import LinkError
from .geo import GeoPoint
from .modes import Model

ENV_VAR = "PLANSYS_BRIDGE_SITL_DIR"
BINARIES: Mapping[Model, str] = {"copter": "arducopter", "rover": "ardurover"}
DEFAULT_PARAMS: Mapping[Model, str] = {"copter": "copter.parm", "rover": "rover.parm"}
FRAMES: Mapping[Model, str] = {"copter": "+", "rover": "rover"}
BASE_PORT = 5760
RC_IN_PORT = 5501
DEFAULT_HOME = GeoPoint(-35.363261, 149.165230, 584.0)
"""ArduPilot's own default SITL home (CMAC, Canberra)."""


def sitl_dir(environ: Mapping[str, str] | None = None) -> Path | None:
    """The folder named by ``PLANSYS_BRIDGE_SITL_DIR``, or None when it is unset."""
    value = (os.environ if environ is None else environ).get(ENV_VAR, "").strip()
    return Path(value) if value else None


def missing(folder: Path | None, models: tuple[Model, ...] = ("copter", "rover")) -> str | None:
    """Why SITL cannot run from ``folder`` (None when it can): names what is missing."""
    if folder is None:
        return f"set {ENV_VAR} to a folder holding arducopter, ardurover and their .parm files"
    for model in models:
        binary = folder / BINARIES[model]
        if not os.access(binary, os.X_OK):
            return f"{ENV_VAR}={folder}: no executable {BINARIES[model]} there"
        if not (folder / DEFAULT_PARAMS[model]).is_file():
            return f"{ENV_VAR}={folder}: no {DEFAULT_PARAMS[model]} there"
    return None


def instance_ports(instance: int) -> tuple[int, ...]:
    """TCP ports of instance ``N``: SERIAL0, SERIAL1, SERIAL2."""
    base = BASE_PORT + 10 * instance
    return (base, base + 2, base + 3)


def instance_free(instance: int) -> bool:
    """No socket holds the ports of instance ``N`` (another SITL, another test run)."""
    checks = [(socket.SOCK_STREAM, p) for p in instance_ports(instance)]
    checks.append((socket.SOCK_DGRAM, RC_IN_PORT + 10 * instance))
    for kind, port in checks:
        with socket.socket(socket.AF_INET, kind) as probe:
            try:
                probe.bind(("0.0.0.0", port))
            except OSError:
                return False
    return True


@dataclass
class SitlProcess:
    """One ArduCopter / ArduRover SITL instance, started by :meth:`start`."""

    model: Model
    instance: int
    workdir: Path
    speedup: float = 1.0
    home: GeoPoint = DEFAULT_HOME
    heading: float = 0.0
    params: Mapping[str, float] | None = None
    """Parameters written to an extra defaults file after the model's own."""
    folder: Path | None = None
    process: subprocess.Popen[bytes] | None = None

    @property
    def port(self) -> int:
        return BASE_PORT + 10 * self.instance

    @property
    def url(self) -> str:
        """The adapter's link (SERIAL0; its first client starts the clock)."""
        return f"tcp:127.0.0.1:{self.port}"

    @property
    def gcs_url(self) -> str:
        """A second ground station's link (SERIAL1)."""
        return f"tcp:127.0.0.1:{self.port + 2}"

    @property
    def log_path(self) -> Path:
        return self.workdir / "sitl.log"

    def command(self) -> list[str]:
        folder = self.folder or sitl_dir()
        if folder is None:
            raise LinkError(self.url, f"no SITL folder: set {ENV_VAR}")
        defaults = [str(folder / DEFAULT_PARAMS[self.model])]
        if self.params:
            extra = self.workdir / "extra.parm"
            extra.write_text("".join(f"{k} {v:g}\n" for k, v in self.params.items()))
            defaults.append(str(extra))
        h = self.home
        return [
            str(folder / BINARIES[self.model]),
            "-S",
            "--model",
            FRAMES[self.model],
            "--speedup",
            f"{self.speedup:g}",
            "--slave",
            "0",
            "--defaults",
            ",".join(defaults),
            "--sim-address=127.0.0.1",
            "-I",
            str(self.instance),
            "--home",
            f"{h.lat:.7f},{h.lon:.7f},{h.alt:g},{self.heading:g}",
            "-w",
        ]

    def start(self, timeout: float = 30.0) -> SitlProcess:
        """Start the binary and wait until its MAVLink port listens (without connecting:
        a connection would start the simulated clock)."""
        self.workdir.mkdir(parents=True, exist_ok=True)
        argv = self.command()
        with self.log_path.open("wb") as log:
            self.process = subprocess.Popen(
                argv,
                cwd=self.workdir,
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
            )
        deadline = time.monotonic() + timeout
        while not _listening(self.port):
            if self.process.poll() is not None:
                code = self.process.returncode
                raise LinkError(
                    self.url, f"SITL exited with {code} before listening: {self.log_tail()}"
                )
            if time.monotonic() > deadline:
                self.stop()
                raise LinkError(self.url, f"SITL did not listen within {timeout:g} s")
            time.sleep(0.05)
        return self

    def stop(self) -> None:
        """Terminate the process by its pid (then kill it if it lingers)."""
        proc, self.process = self.process, None
        if proc is None or proc.poll() is not None:
            return
        proc.terminate()
        try:
            proc.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            proc.kill()
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=5.0)

    def log_tail(self, lines: int = 10) -> str:
        with contextlib.suppress(OSError):
            text = self.log_path.read_text(errors="replace").splitlines()
            return " | ".join(text[-lines:])
        return ""


def _listening(port: int) -> bool:
    """A TCP socket listens on ``port`` (read from /proc: connecting would start SITL)."""
    state_listen = "0A"
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            rows = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for row in rows:
            fields = row.split()
            listens = len(fields) > 3 and fields[3] == state_listen
            if listens and int(fields[1].rsplit(":", 1)[1], 16) == port:
                return True
    return False
