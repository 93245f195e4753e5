"""Report tests leave no task, thread or asyncio error behind."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def _no_leaks(no_leaks: None) -> None:
    """Opt in to the project's leak check (tests/conftest.py)."""
