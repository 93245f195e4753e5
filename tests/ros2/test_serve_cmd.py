"""``plansys-bridge serve``: another process calls its domain expert over DDS."""

import asyncio
import random
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int64, uint64
from ros2_upstream import Empty_, RawClient

from plansys_bridge.hub.dds_config import loopback_config
from plansys_bridge.hub.dds_participant import SharedDomain

pytestmark = pytest.mark.timeout(90)

MISSION = Path(__file__).resolve().parents[2] / "configs" / "demo_cooking.yaml"


@dataclass
class GetDomainName_Request_(
    IdlStruct, typename="plansys2_msgs::srv::dds_::GetDomainName_Request_"
):
    guid: uint64 = 0
    seq: int64 = 0
    request: Empty_ = field(default_factory=Empty_)


@dataclass
class GetDomainName_Response_(
    IdlStruct, typename="plansys2_msgs::srv::dds_::GetDomainName_Response_"
):
    guid: uint64 = 0
    seq: int64 = 0
    success: bool = False
    name: str = ""
    error_info: str = ""


def test_serve_answers_get_domain_name() -> None:
    domain = random.SystemRandom().randint(1, 232)
    command = [sys.executable, "-m", "plansys_bridge", "serve", str(MISSION)]
    server = subprocess.Popen(
        [*command, "--domain-id", str(domain), "--duration", "30"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    SharedDomain.acquire(domain, loopback_config(domain))
    dp = DomainParticipant(domain)
    try:
        client = RawClient(
            dp, "/domain_expert/get_domain_name", GetDomainName_Request_, GetDomainName_Response_
        )
        reply = asyncio.run(client.call(timeout=40))
        assert reply.success and reply.name == "cooking"
    finally:
        dp.__del__()
        SharedDomain.release(domain)
        server.terminate()
        out, _ = server.communicate(timeout=20)
    assert "serving" in out and "/execute_plan" in out
