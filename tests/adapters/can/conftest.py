"""CAN adapter tests: the performer and the base double back to back on a virtual bus.

Every test gets its own virtual channel name, so no frame crosses tests, and must
leave no task, thread or asyncio error behind.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from can_rig import new_channel

from plansys_bridge.clock import VirtualClock
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.transport import InProcessTransport


@pytest.fixture(autouse=True)
def _no_leaks(no_leaks: None) -> Iterator[None]:
    yield


@pytest.fixture
def channel() -> str:
    return new_channel()


@pytest.fixture
def hub() -> Hub:
    """A hub on a fresh virtual clock; run coroutines with ``run(coro, hub.clock)``."""
    return Hub(InProcessTransport(), VirtualClock())
