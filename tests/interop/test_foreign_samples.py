"""Samples a foreign DDS node gets wrong are dropped, one log line each naming topic and
writer; the good ones around them still arrive. The foreign node's types are the
test's own (tests/interop/plansys2_peer.py), typed from upstream's .msg texts."""

from __future__ import annotations

import asyncio
import logging
import random
import time
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from plansys2_peer import (
    FEEDBACK,
    REQUEST,
    ActionExecution_,
    ActionPerformerStatus_,
)

from plansys_bridge.clock import WallClock
from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds import DdsTransport
from plansys_bridge.hub.dds_checks import domain_check
from plansys_bridge.hub.hub import Hub

pytestmark = pytest.mark.timeout(60)

BAD_EXECUTIONS = [
    (ActionExecution_(type=42, action="move", arguments=["r1", "a", "b"]), "not one of"),
    (ActionExecution_(type=REQUEST, action="fly", arguments=["r1", "a", "b"]), "unknown action"),
    (ActionExecution_(type=REQUEST, action="move", arguments=["r1"]), "takes 3 arguments"),
    (
        ActionExecution_(type=FEEDBACK, action="move", arguments=["r1", "a", "b"], completion=7.0),
        "outside 0..1",
    ),
    (
        ActionExecution_(
            type=FEEDBACK, action="move", arguments=["r1", "a", "b"], completion=float("nan")
        ),
        "not a finite number",
    ),
]
BAD_STATUSES = [
    (ActionPerformerStatus_(state=3, action="move", node_name="x"), "not one of"),
    (ActionPerformerStatus_(state=1, action="dance", node_name="x"), "unknown action"),
]


def test_foreign_samples_are_dropped_with_one_line_naming_topic_and_writer(
    caplog: pytest.LogCaptureFixture,
) -> None:
    domain_id = random.SystemRandom().randint(1, 232)
    caplog.set_level(logging.WARNING, logger="plansys_bridge.hub.dds")

    async def main() -> tuple[list[Any], list[Any], int]:
        transport = DdsTransport(domain_id, check=domain_check({"move": 3}))
        hub = Hub(transport, WallClock())
        await hub.start()
        got: list[Any] = []
        statuses: list[Any] = []
        hub.subscribe(hm.Topics.ACTIONS_HUB, got.append)
        hub.subscribe(hm.Topics.PERFORMERS_STATUS, statuses.append)
        foreign = DomainParticipant(domain_id)
        try:
            hub_writer = DataWriter(foreign, Topic(foreign, "rt/actions_hub", ActionExecution_))
            status_writer = DataWriter(
                foreign, Topic(foreign, "rt/performers_status", ActionPerformerStatus_)
            )
            deadline = time.monotonic() + 10
            while (
                hub_writer.get_publication_matched_status().current_count < 1
                or status_writer.get_publication_matched_status().current_count < 1
            ):
                assert time.monotonic() < deadline, "the foreign writers never matched"
                await asyncio.sleep(0.01)
            for sample, _ in BAD_EXECUTIONS:
                hub_writer.write(sample)
            for status, _ in BAD_STATUSES:
                status_writer.write(status)
            hub_writer.write(
                ActionExecution_(type=REQUEST, action="move", arguments=["r1", "a", "b"])
            )
            status_writer.write(ActionPerformerStatus_(state=1, action="move", node_name="ok"))
            while not (got and statuses):
                assert time.monotonic() < deadline, "the good samples never arrived"
                await asyncio.sleep(0.01)
            await asyncio.sleep(0.1)
            return got, statuses, transport.dropped
        finally:
            foreign.__del__()
            await hub.close()

    got, statuses, dropped = asyncio.run(main())
    assert [(m.type, m.action) for m in got] == [(hm.ExecutionType.REQUEST, "move")]
    assert [s.node_name for s in statuses] == ["ok"]
    assert dropped == len(BAD_EXECUTIONS) + len(BAD_STATUSES)
    lines = [r.getMessage() for r in caplog.records if "dropped a sample" in r.getMessage()]
    assert len(lines) == dropped
    expected = [("rt/actions_hub", why) for _, why in BAD_EXECUTIONS] + [
        ("rt/performers_status", why) for _, why in BAD_STATUSES
    ]
    for topic, why in expected:
        assert any(
            line.startswith(f"{topic}: dropped a sample from writer ") and why in line
            for line in lines
        ), (topic, why, lines)


def test_messages_of_another_plan_are_dropped_once_a_plan_runs() -> None:
    plans: set[str] = set()
    check = domain_check({"move": 3}, plans)
    other = hm.ActionExecution(
        hm.ExecutionType.FINISH, "r1", "move", ("r1", "a", "b"), request_id="theirs/0/2"
    )
    assert check(hm.Topics.ACTIONS_HUB, other) is None  # no plan yet: nothing to compare
    plans.add("mine")
    assert check(hm.Topics.ACTIONS_HUB, other) == "plan id 'theirs' is not a plan of this executor"
    ours = hm.ActionExecution(
        hm.ExecutionType.FINISH, "r1", "move", ("r1", "a", "b"), request_id="mine/1/0"
    )
    assert check(hm.Topics.ACTIONS_HUB, ours) is None
    plan = hm.ExecutingPlan(hm.Plan((hm.PlanItem(0.0, "(move r1 a b)", 1.0),)), "theirs")
    assert "not a plan of this executor" in (check(hm.Topics.EXECUTING_PLAN, plan) or "")
    bad_item = hm.ExecutingPlan(hm.Plan((hm.PlanItem(0.0, "(fly r1)", 1.0),)), "mine")
    assert "unknown action 'fly'" in (check(hm.Topics.EXECUTING_PLAN, bad_item) or "")
