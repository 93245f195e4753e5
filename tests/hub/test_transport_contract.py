"""Every built-in transport keeps the transport contract (plansys_bridge.testing)."""

from __future__ import annotations

import random

import pytest

from plansys_bridge.hub.transport_kinds import TRANSPORTS
from plansys_bridge.testing import TransportContract


def test_every_builtin_transport_has_a_contract_class() -> None:
    tested = {c.transport for c in TransportContract.__subclasses__() if c.__module__ == __name__}
    assert tested == set(TRANSPORTS.builtin)


class TestInProcessContract(TransportContract):
    transport = "inprocess"


class TestDdsContract(TransportContract):
    """Two hubs on Cyclone DDS (loopback), on a domain of their own."""

    transport = "dds"
    settings = {"domain_id": random.randint(150, 230)}

    @pytest.fixture(autouse=True)
    def _cyclonedds(self) -> None:
        pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")
