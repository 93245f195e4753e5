"""Messages built on the auction's hot paths equal those built the ordinary way."""

from __future__ import annotations

from plansys_bridge.hub.messages import ActionExecution, ExecutionType, readdressed


def test_readdressed_changes_the_node_only() -> None:
    reject = ActionExecution(
        ExecutionType.REJECT, "", "move", ("r1", "a"), status="s", bid=2.5, request_id="q"
    )
    to_p7 = readdressed(reject, "p7")
    assert to_p7 == ActionExecution(
        ExecutionType.REJECT, "p7", "move", ("r1", "a"), status="s", bid=2.5, request_id="q"
    )
    assert reject.node_id == ""  # the template is left as it was
    assert readdressed(to_p7, "") == reject
