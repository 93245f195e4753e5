"""The range checks every message received over DDS passes (hub/dds_checks.py)."""

from __future__ import annotations

import math

import pytest

from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds_checks import check_sample

RESPONSE = hm.ExecutionType.RESPONSE


@pytest.mark.parametrize(
    ("bid", "completion", "reason"),
    [
        (None, 0.0, None),
        (0.0, 1.0, None),
        (math.inf, 0.5, None),
        (-0.0, 0.0, None),
        (-1e-9, 0.0, "bid -1e-09 is not a cost >= 0"),
        (-math.inf, 0.0, "bid -inf is not a cost >= 0"),
        (math.nan, 0.0, "bid nan is not a cost >= 0"),
        (1.0, -0.5, "completion -0.5 is outside 0..1"),
        (1.0, 1.5, "completion 1.5 is outside 0..1"),
        (None, math.nan, "completion nan is outside 0..1"),
    ],
)
def test_bids_are_costs_and_completion_a_fraction(
    bid: float | None, completion: float, reason: str | None
) -> None:
    msg = hm.ActionExecution(RESPONSE, "p1", "move", bid=bid, completion=completion)
    assert check_sample(hm.Topics.ACTIONS_HUB, msg) == reason


def test_other_messages_keep_their_checks() -> None:
    info = hm.ActionExecutionInfo(
        hm.ActionStatus.EXECUTING, 0.0, 0.0, "(move r a b)", "move", duration=-1.0
    )
    assert check_sample(hm.Topics.ACTION_EXECUTION_INFO, info) == "duration -1.0 is negative"
    assert check_sample(hm.Topics.KNOWLEDGE, hm.Knowledge()) is None
