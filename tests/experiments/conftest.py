"""Experiment tests check that a run leaves no task, thread or asyncio error behind."""

from __future__ import annotations

from collections.abc import Iterator

import pytest


@pytest.fixture(autouse=True)
def _no_leaks(no_leaks: None) -> Iterator[None]:
    yield
