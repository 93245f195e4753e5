"""Running an external solver: its own temporary folder and a timeout that holds.

Solvers such as TFD and Fast Downward are driver scripts that start further
processes; killing only the direct child leaves the search running and eating a
core. Each run therefore gets a new session (process group) and the whole group is
terminated on timeout, then killed if it does not stop within a grace period.
"""

from __future__ import annotations

import os
import signal
import subprocess
import tempfile
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path

from plansys_bridge.errors import PlanningError

GRACE_PERIOD_S = 1.0
"""Time a solver gets between SIGTERM and SIGKILL."""


@dataclass(frozen=True)
class ProcessResult:
    command: tuple[str, ...]
    returncode: int | None
    """None when the process had to be killed after the timeout."""
    stdout: str
    stderr: str
    elapsed_s: float
    timed_out: bool

    def describe(self, max_lines: int = 15) -> str:
        """``lpg exited with status 3; stderr: ...`` for error messages."""
        name = Path(self.command[0]).name if self.command else "process"
        if self.timed_out:
            head = f"{name} was stopped after {self.elapsed_s:.1f} s (timeout)"
        elif self.returncode is not None and self.returncode < 0:
            head = f"{name} was killed by signal {-self.returncode}"
        else:
            head = f"{name} exited with status {self.returncode}"
        tail = _tail(self.stderr, max_lines) or _tail(self.stdout, max_lines)
        which = "stderr" if self.stderr.strip() else "stdout"
        return f"{head}; {which}: {tail}" if tail else head


def _tail(text: str, max_lines: int) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return " | ".join(lines[-max_lines:])


def run_process(
    command: Sequence[str | os.PathLike[str]],
    *,
    cwd: str | os.PathLike[str],
    timeout: float,
    env: Mapping[str, str] | None = None,
) -> ProcessResult:
    """Run ``command`` in ``cwd``; on timeout stop its whole process group."""
    argv = tuple(os.fspath(c) for c in command)
    started = time.monotonic()
    try:
        proc = subprocess.Popen(
            argv,
            cwd=cwd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            errors="replace",
            env=dict(env) if env is not None else None,
            start_new_session=True,
        )
    except OSError as exc:
        raise PlanningError(f"cannot start {argv[0]}: {exc}") from exc
    timed_out = False
    try:
        stdout, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        timed_out = True
        stdout, stderr = _stop_group(proc)
    except BaseException:
        _stop_group(proc)
        raise
    finally:
        # Anything the solver left running in its group goes with it.
        _signal_group(proc.pid, signal.SIGKILL)
    return ProcessResult(
        argv,
        None if timed_out else proc.returncode,
        stdout or "",
        stderr or "",
        time.monotonic() - started,
        timed_out,
    )


def _signal_group(pgid: int, sig: signal.Signals) -> None:
    with suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, sig)


def _stop_group(proc: subprocess.Popen[str]) -> tuple[str, str]:
    _signal_group(proc.pid, signal.SIGTERM)
    try:
        return proc.communicate(timeout=GRACE_PERIOD_S)
    except subprocess.TimeoutExpired:
        _signal_group(proc.pid, signal.SIGKILL)
    try:
        return proc.communicate(timeout=GRACE_PERIOD_S)
    except subprocess.TimeoutExpired:
        # A grandchild that left the group still holds the pipes: stop reading.
        proc.kill()
        for stream in (proc.stdout, proc.stderr):
            if stream is not None:
                stream.close()
        proc.wait()
        return "", ""


@contextmanager
def run_folder(solver: str, keep: bool = False) -> Iterator[Path]:
    """A fresh temporary folder for one solver run; removed afterwards unless ``keep``."""
    if keep:
        yield Path(tempfile.mkdtemp(prefix=f"plansys_bridge_{solver}_"))
        return
    with tempfile.TemporaryDirectory(prefix=f"plansys_bridge_{solver}_") as folder:
        yield Path(folder)
