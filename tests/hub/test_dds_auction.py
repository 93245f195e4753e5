"""The auction through DdsTransport: executor and performer on separate DDS participants."""

from __future__ import annotations

import asyncio
import random
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from plansys_bridge.clock import WallClock
from plansys_bridge.hub.auction import ActionClient, ActionOutcome
from plansys_bridge.hub.dds import DdsTransport
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import ActionExecution, ExecutionType
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer

pytestmark = pytest.mark.timeout(60)


def test_normal_action_message_order_over_dds(hub_recorder: Any) -> None:
    """REQUEST, RESPONSE, CONFIRM, FEEDBACK x2, FINISH, as on the in-process hub.

    Durations are mission seconds on a wall clock running 10x fast: the action takes
    3 s (0.3 s real) with feedback every second, so two FEEDBACKs precede FINISH.
    """
    clock = WallClock(time_scale=0.1)
    domain = random.SystemRandom().randint(1, 232)

    async def main() -> tuple[ActionOutcome, list[tuple[str, str]], list[ActionExecution]]:
        executor_hub = Hub(DdsTransport(domain), clock)
        performer_hub = Hub(DdsTransport(domain), clock)
        await executor_hub.start()
        await performer_hub.start()
        performer = SimulatedPerformer(
            PerformerContext(performer_hub, clock),
            "r1_move",
            {"move": ["r1"]},
            durations={"move": 3.0},
            feedback_period=1.0,
        )
        try:
            for transport in (executor_hub.transport, performer_hub.transport):
                assert isinstance(transport, DdsTransport)
                await transport.wait_for_peers(1, timeout=5)
            await performer.start()
            rec = hub_recorder(executor_hub)
            client = ActionClient(executor_hub, "move", ["r1", "a", "b"], request_id="plan1:0")
            outcome = await asyncio.wait_for(client.run(), 10)
            await asyncio.sleep(0.05)
            rec.close()
            return outcome, rec.kinds(), rec.executions()
        finally:
            await performer.stop()
            await performer_hub.close()
            await executor_hub.close()

    outcome, kinds, executions = asyncio.run(main())
    assert kinds == [
        ("REQUEST", ""),
        ("RESPONSE", "r1_move"),
        ("CONFIRM", "r1_move"),
        ("FEEDBACK", "r1_move"),
        ("FEEDBACK", "r1_move"),
        ("FINISH", "r1_move"),
    ]
    # The project fields crossed DDS on the wrapper topic, each message exactly once.
    assert all(m.request_id == "plan1:0" for m in executions), executions
    assert all(m.arguments == ("r1", "a", "b") for m in executions)
    assert executions[-1].type == ExecutionType.FINISH and executions[-1].success
    assert outcome.success and outcome.performer == "r1_move"
    assert outcome.completion == 1.0
