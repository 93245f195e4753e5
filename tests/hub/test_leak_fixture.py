"""The ``no_leaks`` fixture really fails tests that leave things behind."""

from __future__ import annotations

import sys
import threading
import types
from pathlib import Path

import pytest

CONFTEST = Path(__file__).resolve().parents[1] / "conftest.py"

LEAKY_TESTS = """
import asyncio
import threading

import pytest

import leak_switch
from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.transport import InProcessTransport

pytestmark = pytest.mark.usefixtures("no_leaks")


def test_clean():
    async def main():
        await asyncio.sleep(5)
    run(main(), VirtualClock())


def test_leaves_a_task():
    async def main():
        asyncio.ensure_future(asyncio.sleep(100), loop=asyncio.get_running_loop())
    run(main(), VirtualClock())


def test_leaves_a_thread():
    threading.Thread(target=leak_switch.release.wait, name="leaky-worker").start()


@pytest.mark.allow_threads("leaky-")
def test_allowed_thread():
    threading.Thread(target=leak_switch.release.wait, name="leaky-allowed").start()


def test_task_exception_never_retrieved():
    async def boom():
        raise ValueError("nobody looked")

    async def main():
        asyncio.ensure_future(boom())
        await asyncio.sleep(1)

    run(main(), VirtualClock())


def test_subscriber_error():
    async def main():
        t = InProcessTransport()
        await t.start()
        t.subscribe("x", lambda m: 1 / 0)
        t.publish("x", 1)
        await asyncio.sleep(0)
    run(main(), VirtualClock())
"""


@pytest.mark.allow_asyncio_errors  # the inner run's subscriber error is logged here too
def test_no_leaks_fails_leaking_tests(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    release = threading.Event()
    monkeypatch.setitem(sys.modules, "leak_switch", types.SimpleNamespace(release=release))
    monkeypatch.setenv("PLANSYS_BRIDGE_TEST_THREAD_GRACE", "0.05")
    pytester.makeconftest(CONFTEST.read_text())
    pytester.makepyfile(test_leaky=LEAKY_TESTS)
    try:
        result = pytester.runpytest_inprocess("-p", "no:cacheprovider", "-p", "no:timeout")
    finally:
        release.set()
    result.assert_outcomes(passed=6, errors=4)
    out = result.stdout.str()
    assert "ERROR at teardown of test_leaves_a_task" in out
    assert "asyncio tasks still pending when the loop closed" in out
    assert "ERROR at teardown of test_leaves_a_thread" in out
    assert "leaky-worker (daemon=False)" in out
    assert "ERROR at teardown of test_subscriber_error" in out
    assert "subscriber of 'x' raised ZeroDivisionError" in out
    assert "ERROR at teardown of test_task_exception_never_retrieved" in out
    assert "Task exception was never retrieved" in out
    assert "test_allowed_thread" not in out.split("short test summary")[-1]
