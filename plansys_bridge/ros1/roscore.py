"""Start Debian's roscore on loopback, on a free port, for tests, demos and benchmarks.

Debian's stock ``/etc/ros/roscore.xml`` starts the rosout node, which binds all
interfaces whatever ``ROS_IP`` says; the copy used here leaves it out, and
``ROS_IP=127.0.0.1`` keeps the master itself on loopback. Each roscore gets its own
port (not 11311) and ``ROS_HOME`` so parallel runs never meet.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import xmlrpc.client
from pathlib import Path
from typing import Any

from plansys_bridge.ros1.errors import MasterUnreachable, Ros1Error

__all__ = ["DEBIAN_PACKAGES", "Roscore", "free_port", "missing_ros1"]

DEBIAN_PACKAGES = (
    "ros-core python3-rospy python3-actionlib python3-move-base-msgs "
    "python3-std-msgs python3-nav-msgs"
)
"""What the real-ROS 1 tests need (Debian 12 names)."""

SYSTEM_PYTHON = "/usr/bin/python3"
_PEER_MODULES = "rospy, actionlib, move_base_msgs.msg, std_msgs.msg, nav_msgs.msg"


def missing_ros1() -> str | None:
    """Why the real ROS 1 cannot be used here (None: roscore and rospy are there)."""
    if shutil.which("roscore") is None:
        return f"roscore not found (Debian packages: {DEBIAN_PACKAGES})"
    if not Path(SYSTEM_PYTHON).exists():
        return f"{SYSTEM_PYTHON} not found (rospy peers run with the system python)"
    probe = subprocess.run(
        [SYSTEM_PYTHON, "-c", f"import {_PEER_MODULES}"],
        capture_output=True,
        text=True,
        timeout=60,
        env=ros_env("http://127.0.0.1:1"),
    )
    if probe.returncode != 0:
        last = (probe.stderr.strip().splitlines() or ["?"])[-1]
        return (
            f"{SYSTEM_PYTHON} cannot import rospy peers ({last}); "
            f"Debian packages: {DEBIAN_PACKAGES}"
        )
    return None


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def ros_env(master_uri: str, home: Path | None = None) -> dict[str, str]:
    """Environment for ROS 1 processes on loopback talking to ``master_uri``."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "PYTHON"))}
    env.update(ROS_MASTER_URI=master_uri, ROS_IP="127.0.0.1")
    if home is not None:
        env["ROS_HOME"] = str(home)
        env["ROS_LOG_DIR"] = str(home / "log")
    return env


class Roscore:
    """``with Roscore() as core:`` a master at ``core.uri`` until the block ends."""

    def __init__(self, port: int | None = None, workdir: Path | None = None) -> None:
        self.port = port or free_port()
        self.uri = f"http://127.0.0.1:{self.port}"
        self._own_dir = workdir is None
        self.workdir = workdir or Path(tempfile.mkdtemp(prefix="roscore-"))
        self.process: subprocess.Popen[bytes] | None = None

    def env(self) -> dict[str, str]:
        return ros_env(self.uri, self.workdir)

    def start(self, timeout: float = 30.0) -> None:
        etc = self.workdir / "etc"
        etc.mkdir(parents=True, exist_ok=True)
        source = Path("/etc/ros/roscore.xml")
        text = source.read_text() if source.exists() else "<launch>\n</launch>\n"
        (etc / "roscore.xml").write_text(re.sub(r"\s*<node [^>]*rosout[^>]*/>", "", text))
        env = self.env()
        env["ROS_ETC_DIR"] = str(etc)
        self.process = subprocess.Popen(
            ["roscore", "-p", str(self.port)],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=(self.workdir / "roscore.out").open("wb"),
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                out = (self.workdir / "roscore.out").read_text(errors="replace")[-2000:]
                raise Ros1Error(f"roscore on port {self.port} exited: {out}")
            try:
                xmlrpc.client.ServerProxy(self.uri).getPid("/probe")
                return
            except OSError:
                time.sleep(0.1)
        self.stop()
        raise MasterUnreachable(f"roscore at {self.uri} did not answer within {timeout} s")

    def stop(self) -> None:
        process, self.process = self.process, None
        if process is None or process.poll() is not None:
            return
        # roslaunch runs rosmaster in a process group of its own: ask the master for
        # its pid first, so it cannot outlive a roslaunch that had to be killed.
        master_pid = self._master_pid()
        os.killpg(process.pid, signal.SIGINT)
        try:
            process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        if master_pid is not None:
            _end(master_pid)

    def _master_pid(self) -> int | None:
        try:
            reply: Any = xmlrpc.client.ServerProxy(self.uri).getPid("/roscore")
            code, _, pid = reply
        except (OSError, ValueError, TypeError, xmlrpc.client.Error):
            return None
        return int(pid) if code == 1 and pid != os.getpid() else None

    def close(self) -> None:
        self.stop()
        if self._own_dir:
            shutil.rmtree(self.workdir, ignore_errors=True)

    def __enter__(self) -> Roscore:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _end(pid: int, grace: float = 5.0) -> None:
    """SIGTERM ``pid`` if it still runs, SIGKILL after ``grace`` seconds."""
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    deadline = time.monotonic() + grace
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.05)
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGKILL)
