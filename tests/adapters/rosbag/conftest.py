"""Fixtures for the ROS-bag adapter tests: the demo bags and the leak check."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbag_testdata import DEMO_BAGS


@pytest.fixture
def demo_bags() -> Path:
    """The repository's generated demo bags."""
    return DEMO_BAGS


@pytest.fixture(autouse=True)
def _no_leaks(no_leaks: None) -> None:
    """Every test here must leave no task, thread or asyncio error behind."""
