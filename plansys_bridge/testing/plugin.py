"""pytest plugin (entry point ``pytest11``): marks the contract tests.

Every test inherited from a contract of :mod:`plansys_bridge.testing` (performer,
solver, transport) gets the ``contract`` marker, so ``pytest -m contract`` runs just
the contract of a plugin package.
"""

from __future__ import annotations

import pytest


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "contract: a contract test (plansys_bridge.testing)")
    config.addinivalue_line(
        "markers", "allow_asyncio_errors: the test provokes errors the asyncio logger reports"
    )


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        cls = getattr(item, "cls", None)
        if cls is not None and any(
            base.__module__.startswith("plansys_bridge.testing.") for base in cls.__mro__[1:]
        ):
            item.add_marker(pytest.mark.contract)
