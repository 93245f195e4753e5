"""pytest plugin (entry point ``pytest11``): marks the performer contract tests.

Every test inherited from :class:`~plansys_bridge.testing.PerformerContract` gets the
``contract`` marker, so ``pytest -m contract`` runs just the contract of an adapter.
"""

from __future__ import annotations

import pytest


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "contract: a performer contract test (plansys_bridge.testing)"
    )


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    from plansys_bridge.testing.contract import PerformerContract

    for item in items:
        cls = getattr(item, "cls", None)
        if cls is not None and issubclass(cls, PerformerContract):
            item.add_marker(pytest.mark.contract)
