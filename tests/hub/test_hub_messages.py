"""Messages built on the auction's hot paths equal those built the ordinary way."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionExecutionInfo,
    ActionStatus,
    ExecutionType,
    execution_info,
    readdressed,
)


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


_TEXT = st.text(max_size=8)
_STAMP = st.floats(allow_nan=False)


@given(
    status=st.sampled_from(ActionStatus),
    start=_STAMP,
    stamp=_STAMP,
    full_name=_TEXT,
    action=_TEXT,
    arguments=st.lists(_TEXT, max_size=3).map(tuple),
    duration=_STAMP,
    completion=_STAMP,
    message=_TEXT,
)
def test_execution_info_equals_the_constructor(
    status: ActionStatus,
    start: float,
    stamp: float,
    full_name: str,
    action: str,
    arguments: tuple[str, ...],
    duration: float,
    completion: float,
    message: str,
) -> None:
    fast = execution_info(
        status, start, stamp, full_name, action, arguments, duration, completion, message
    )
    slow = ActionExecutionInfo(
        status, start, stamp, full_name, action, arguments, duration, completion, message
    )
    assert fast == slow
    assert type(fast) is ActionExecutionInfo
    assert fast.__dict__ == slow.__dict__
    assert hash(fast) == hash(slow)
    assert list(fast.__dict__) == list(slow.__dict__)  # same field order (repr, bags)
