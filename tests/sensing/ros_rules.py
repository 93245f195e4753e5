"""Shared by the ROS sensing tests: one rule loaded against the sensing test domain,
and a wait for the knowledge to show what the rule wrote."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from plansys_bridge.clock import WallClock
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.pddl.parser import parse_domain
from plansys_bridge.sensing.engine import SensingEngine
from plansys_bridge.sensing.load import load_rules

DOMAIN = Path(__file__).resolve().parents[1] / "data" / "sensing_bases.pddl"


def knowledge() -> ProblemExpert:
    k = ProblemExpert(parse_domain(DOMAIN.read_text()))
    k.add_instance("r2d2", "robot")
    return k


def engine(k: ProblemExpert, *rules: dict[str, Any], **mission: Any) -> SensingEngine:
    config = SimpleNamespace(
        sensing=list(rules), performers=[], source="<test>", base_dir=DOMAIN.parent, **mission
    )
    return SensingEngine(load_rules(config, k), k, WallClock())


async def wait_until(check: Any, timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < deadline, "the knowledge never showed the sensed value"
        await asyncio.sleep(0.05)
