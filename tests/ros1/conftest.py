"""Real ROS 1 for the interop tests: Debian's roscore and rospy peers.

The peers (tests/ros1/peers/*.py) are rospy programs run with the system
``/usr/bin/python3``; the project itself never imports rospy. Without Debian's
ROS 1 packages every test here skips with a reason naming them. roscore runs on
loopback, on a free port per session (not 11311), with its rosout node left out
(it would bind all interfaces).
"""

from __future__ import annotations

import functools
import os
import queue
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from plansys_bridge.ros1.roscore import SYSTEM_PYTHON, Roscore, missing_ros1

PEERS = Path(__file__).parent / "peers"


@functools.cache
def _missing() -> str | None:
    return missing_ros1()


@pytest.fixture(autouse=True)
def _no_leaks(no_leaks: None) -> Iterator[None]:
    yield


@pytest.fixture(scope="session")
def ros1_available() -> None:
    reason = _missing()
    if reason is not None:
        pytest.skip(f"real ROS 1 not available: {reason}")


@pytest.fixture(scope="session")
def roscore(ros1_available: None, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Roscore]:
    """One roscore for the session (tests that kill the master start their own)."""
    core = Roscore(workdir=tmp_path_factory.mktemp("roscore"))
    core.start()
    try:
        yield core
    finally:
        core.close()


class Peer:
    """A rospy program; ``expect(text)`` waits for a line starting with ``text``."""

    def __init__(self, script: str, args: list[str], env: dict[str, str]) -> None:
        self.process = subprocess.Popen(
            [SYSTEM_PYTHON, str(PEERS / script), *args],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            start_new_session=True,
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        self._reader = threading.Thread(target=self._read, name=f"peer-{script}", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.put(line.rstrip("\n"))

    def expect(self, prefix: str, timeout: float = 30.0) -> str:
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no line {prefix!r} in {timeout} s; saw {self.seen[-20:]}")
            try:
                line = self.lines.get(timeout=left)
            except queue.Empty:
                continue
            self.seen.append(line)
            if line.startswith(prefix):
                return line

    def stop(self) -> None:
        if self.process.poll() is None:
            os.killpg(self.process.pid, 9)
        self.process.wait()
        self._reader.join(timeout=5)


PeerStarter = Callable[..., Peer]


@pytest.fixture
def start_peer(roscore: Roscore) -> Iterator[PeerStarter]:
    """``start_peer("talker.py", *args, core=...)``: a rospy peer, up ("ready"); all stop after."""
    started: list[Peer] = []

    def start(
        script: str,
        *args: str,
        core: Roscore = roscore,
        env: dict[str, str] | None = None,
        ready: bool = True,
    ) -> Peer:
        peer = Peer(script, list(args), env if env is not None else core.env())
        started.append(peer)
        if ready:
            peer.expect("ready")
        return peer

    try:
        yield start
    finally:
        for peer in started:
            peer.stop()
