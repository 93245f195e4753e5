"""Fixtures for the ROS-bag adapter tests: the shared real bags and the demo bags."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbag_testdata import DEMO_BAGS, SHARED_BAGS


@pytest.fixture
def shared_bags() -> Path:
    """../shared/bags beside the repository (real recordings); skip when absent."""
    if not (SHARED_BAGS / "rl_test1.bag").is_file():
        pytest.skip(f"real bags not found at {SHARED_BAGS.resolve()}")
    return SHARED_BAGS.resolve()


@pytest.fixture
def demo_bags() -> Path:
    """The repository's generated demo bags."""
    return DEMO_BAGS


@pytest.fixture(autouse=True)
def _no_leaks(no_leaks: None) -> None:
    """Every test here must leave no task, thread or asyncio error behind."""
