"""Execution records: what counts as an action's execution time (the paper's metric)."""

from __future__ import annotations

import pytest

from plansys_bridge.execution.results import ActionRecord, ExecutionResult, efficiency_text
from plansys_bridge.hub.messages import ActionStatus


def test_execution_time_counts_the_performers_work_only() -> None:
    waited = ActionRecord("(cook r1)", ActionStatus.SUCCEEDED, start=0.0, confirmed=4.0, end=9.0)
    assert waited.execution_time == 5.0
    never_served = ActionRecord("(cook r2)", ActionStatus.FAILED, start=0.0, end=9.0)
    assert never_served.execution_time == 0.0
    no_performer = ActionRecord("(note r1)", ActionStatus.SUCCEEDED, start=1.0, end=3.0)
    assert no_performer.execution_time == 2.0
    halted = ActionRecord("(move r1)", ActionStatus.CANCELLED, start=0.0, confirmed=0.0, end=2.5)
    assert halted.execution_time == 2.5
    assert ActionRecord("(move r1)").execution_time == 0.0


def test_efficiency_is_summed_execution_time_over_total_time() -> None:
    actions = [
        ActionRecord("(a)", ActionStatus.SUCCEEDED, start=0.0, confirmed=0.0, end=10.0),
        ActionRecord("(b)", ActionStatus.SUCCEEDED, start=0.0, confirmed=0.0, end=10.0),
        ActionRecord("(c)", ActionStatus.SUCCEEDED, start=10.0, confirmed=10.0, end=15.0),
    ]
    result = ExecutionResult(True, "succeeded", actions, started=0.0, finished=20.0)
    assert result.efficiency() == pytest.approx(25.0 / 20.0)
    assert result.efficiency_percent == pytest.approx(125.0)
    assert ExecutionResult(True, "succeeded").efficiency() == 0.0


def test_efficiency_is_not_shown_when_no_action_succeeded() -> None:
    """Two robots failing side by side worked 200 % of the time, and achieved nothing."""
    failed = [
        ActionRecord("(a)", ActionStatus.FAILED, start=0.0, confirmed=0.0, end=10.0),
        ActionRecord("(b)", ActionStatus.FAILED, start=0.0, confirmed=0.0, end=10.0),
    ]
    result = ExecutionResult(False, "failed", failed, started=0.0, finished=10.0)
    assert result.efficiency_percent == pytest.approx(200.0)
    assert efficiency_text(result) == "n/a (no action succeeded)"
    assert "efficiency n/a (no action succeeded)" in result.summary()
    assert "200" not in result.summary()
    result.actions.append(
        ActionRecord("(c)", ActionStatus.SUCCEEDED, start=10.0, confirmed=10.0, end=15.0)
    )
    result.finished = 20.0
    assert efficiency_text(result) == "125.0 %"
