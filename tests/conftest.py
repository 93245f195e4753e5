"""Shared test fixtures.

``no_leaks`` fails a test that leaves asyncio tasks still pending when its event loop
is closed, threads still running after it, or errors logged by asyncio (an exception
in a hub subscriber, a task exception never retrieved). Hub and performer tests use it
on every test; another folder opts in with a conftest.py containing::

    import pytest

    @pytest.fixture(autouse=True)
    def _no_leaks(no_leaks):
        yield

or per module with ``pytestmark = pytest.mark.usefixtures("no_leaks")``.
A test that knowingly keeps a library thread alive marks it with
``@pytest.mark.allow_threads("thread-name-prefix", ...)``; one that provokes
asyncio errors on purpose uses ``@pytest.mark.allow_asyncio_errors``.
"""

from __future__ import annotations

import asyncio
import asyncio.runners
import gc
import logging
import os
import signal
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest
from hypothesis import settings

from plansys_bridge.clock import VirtualClock
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, Topics
from plansys_bridge.hub.transport import InProcessTransport

pytest_plugins = ["pytester"]

# The suite interrupts the processes it starts (safe stops on SIGINT) and itself
# (tests/cli/test_interrupts.py). A job started in the background by a
# non-interactive shell inherits SIGINT ignored, and so would every process the
# tests start; Python's own handler back in place gives them the default again.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# CI (CI=true) checks the same examples of each property on every run, so a change
# lands or not on its own merits, not on the examples a run happened to draw; other
# runs draw new examples each time, which is how new counterexamples are found.
# HYPOTHESIS_PROFILE=ci or =random picks one explicitly.
settings.register_profile("ci", derandomize=True, database=None)
settings.register_profile("random")
settings.load_profile(
    os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if os.environ.get("CI") else "random")
)


def _thread_grace() -> float:
    """How long threads started by a test get to finish after it (seconds)."""
    return float(os.environ.get("PLANSYS_BRIDGE_TEST_THREAD_GRACE") or "2.0")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "allow_threads(*prefixes): threads whose names start so may outlive the test"
    )
    config.addinivalue_line(
        "markers", "allow_asyncio_errors: the test provokes errors the asyncio logger reports"
    )


class _AsyncioErrors(logging.Handler):
    def __init__(self) -> None:
        super().__init__(level=logging.ERROR)
        self.records: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record.getMessage())


@pytest.fixture
def no_leaks(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Fail the test if it leaves tasks, threads or asyncio errors behind."""
    leaked_tasks: list[str] = []
    original_cancel_all = asyncio.runners._cancel_all_tasks  # type: ignore[attr-defined]

    def watching_cancel_all(loop: asyncio.AbstractEventLoop) -> None:
        # asyncio.run / Runner.close cancel what is still pending: that is the leak.
        # Only the innermost watcher reports (a test may run pytest inside pytest).
        innermost = asyncio.runners._cancel_all_tasks is watching_cancel_all  # type: ignore[attr-defined]
        for task in asyncio.all_tasks(loop) if innermost else ():
            if not task.done():
                leaked_tasks.append(f"{task.get_name()}: {task.get_coro()!r}")
        original_cancel_all(loop)

    monkeypatch.setattr(asyncio.runners, "_cancel_all_tasks", watching_cancel_all)
    errors = _AsyncioErrors()
    asyncio_log = logging.getLogger("asyncio")
    asyncio_log.addHandler(errors)
    threads_before = set(threading.enumerate())
    try:
        yield
    finally:
        monkeypatch.setattr(asyncio.runners, "_cancel_all_tasks", original_cancel_all)

    allowed_prefixes: tuple[str, ...] = ()
    for mark in request.node.iter_markers("allow_threads"):
        allowed_prefixes += tuple(str(a) for a in mark.args)

    def new_threads() -> list[threading.Thread]:
        return [
            t
            for t in threading.enumerate()
            if t not in threads_before
            and t.is_alive()
            and not (allowed_prefixes and t.name.startswith(allowed_prefixes))
        ]

    grace = _thread_grace()
    deadline = time.monotonic() + grace
    while new_threads() and time.monotonic() < deadline:
        time.sleep(0.01)
    problems: list[str] = []
    if leaked_tasks:
        problems.append("asyncio tasks still pending when the loop closed:")
        problems.extend(f"  {t}" for t in leaked_tasks)
    leftover = new_threads()
    if leftover:
        problems.append(f"threads still running {grace:g} s after the test:")
        problems.extend(f"  {t.name} (daemon={t.daemon})" for t in leftover)
    gc.collect(1)  # surfaces "Task exception was never retrieved" (young cycles suffice)
    asyncio_log.removeHandler(errors)
    if errors.records and request.node.get_closest_marker("allow_asyncio_errors") is None:
        problems.append("errors logged by asyncio:")
        problems.extend(f"  {m}" for m in errors.records)
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)


# ---------------------------------------------------------------------- hub helpers


class HubRecorder:
    """Records every message of some hub topics with the loop time it arrived at."""

    def __init__(self, hub: Hub, topics: tuple[str, ...] = (Topics.ACTIONS_HUB,)) -> None:
        self.messages: list[tuple[float, object]] = []
        self._subs = [hub.subscribe(topic, self._on_msg) for topic in topics]

    def _on_msg(self, msg: object) -> None:
        self.messages.append((asyncio.get_running_loop().time(), msg))

    def close(self) -> None:
        for sub in self._subs:
            sub.close()

    def executions(self) -> list[ActionExecution]:
        return [m for _, m in self.messages if isinstance(m, ActionExecution)]

    def kinds(self) -> list[tuple[str, str]]:
        """``[("REQUEST", ""), ("RESPONSE", "p1"), ...]``: type and node of each ActionExecution."""
        return [(m.type.name, m.node_id) for m in self.executions()]

    def timeline(self, *, request_ids: bool = False) -> list[tuple[Any, ...]]:
        """``[(time, type, node), ...]`` of each ActionExecution (+ request_id if asked)."""
        return [
            (round(t, 6), m.type.name, m.node_id, m.request_id)
            if request_ids
            else (round(t, 6), m.type.name, m.node_id)
            for t, m in self.messages
            if isinstance(m, ActionExecution)
        ]


@pytest.fixture
def virtual_hub() -> Hub:
    """A hub on a fresh virtual clock; run the test's coroutine with ``run(coro, hub.clock)``."""
    return Hub(InProcessTransport(), VirtualClock())


@pytest.fixture
def hub_recorder() -> type[HubRecorder]:
    """The :class:`HubRecorder` class: ``rec = hub_recorder(hub)`` inside the running loop."""
    return HubRecorder
