"""ActionExecution's own XCDR1 path gives the generated codec's bytes and messages."""

from __future__ import annotations

import math

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds_codec import ROUTES, wire_sources
from plansys_bridge.hub.dds_execution import PLAIN, WRAPPED, execution_reader
from plansys_bridge.hub.dds_wire import hub_reader
from plansys_bridge.interfaces.dds import dds_type

ROUTE = ROUTES[hm.Topics.ACTIONS_HUB]

texts = st.text(max_size=12)
finite = st.floats(allow_nan=False, allow_infinity=False, width=32)
messages = st.builds(
    hm.ActionExecution,
    type=st.sampled_from(list(hm.ExecutionType)),
    node_id=texts,
    action=texts,
    arguments=st.lists(texts, max_size=4).map(tuple),
    success=st.booleans(),
    completion=finite,
    status=texts,
    bid=st.none() | st.floats(min_value=0, max_value=1e9, allow_nan=False),
    request_id=texts,
)


def _generic_read(ros_type: str, data: bytes) -> hm.ActionExecution:
    """What the generated reader makes of the bytes (merging a wrapper as before)."""
    if ros_type == PLAIN:
        return hub_reader(PLAIN, hm.ActionExecution, lambda x: x)(data)  # type: ignore[no-any-return]
    x = hub_reader(WRAPPED, hm.BridgeActionExecution, lambda x: x)(data)
    return hm.ActionExecution(
        **{**vars(x.execution), "request_id": x.request_id, "bid": x.bid if x.has_bid else None}
    )


@settings(max_examples=300, deadline=None)
@given(st.lists(messages, min_size=1, max_size=6))
def test_bytes_and_messages_are_the_generated_codecs(batch: list[hm.ActionExecution]) -> None:
    """Written and read in a row, as a transport does, so bodies kept from earlier
    samples are reused: every message still comes back as the generic reader reads it."""
    to_plain, to_wrapped = ROUTE.to_bytes
    assert to_wrapped is not None
    readers = {ch.ros_type: ch.read for ch in ROUTE.channels}
    for msg in batch:
        plain, wrapped = wire_sources(hm.Topics.ACTIONS_HUB, msg)
        for ros_type, source, fast in ((PLAIN, plain, to_plain), (WRAPPED, wrapped, to_wrapped)):
            channel = next(c for c in ROUTE.channels if c.ros_type == ros_type)
            data = fast(msg)
            assert data == channel.write(source)
            assert readers[ros_type](data) == _generic_read(ros_type, data)
            assert readers[ros_type](data) == _generic_read(ros_type, data)  # a kept body


def test_a_kept_body_is_not_taken_for_another_of_the_same_length() -> None:
    read = execution_reader(PLAIN, lambda data: pytest.fail("not XCDR1?"))
    to_plain = ROUTE.to_bytes[0]
    first = hm.ActionExecution(hm.ExecutionType.REJECT, "p1", "move", ("r1", "a", "b"))
    second = hm.ActionExecution(hm.ExecutionType.REJECT, "p2", "move", ("r2", "a", "b"))
    assert read(to_plain(first)).arguments == ("r1", "a", "b")
    assert read(to_plain(second)).arguments == ("r2", "a", "b")
    assert read(to_plain(first)) == first


def test_bad_samples_are_refused_as_the_generated_reader_refuses_them() -> None:
    cls = dds_type(PLAIN)
    read = next(c for c in ROUTE.channels if c.ros_type == PLAIN).read
    with pytest.raises(ValueError, match=r"ActionExecution\.type is 42, not one of REQUEST=1"):
        read(cls(type=42).serialize(use_version_2=False))
    with pytest.raises(ValueError, match="completion is nan, not a finite number"):
        read(cls(type=5, completion=math.nan).serialize(use_version_2=False))
    good = ROUTE.to_bytes[0](hm.ActionExecution(hm.ExecutionType.REQUEST, "", "move"))
    for bad in (good[:9], good[:8] + b"\xff\xff\xff\x7f" + good[12:]):
        with pytest.raises(ValueError):
            read(bad)
    with pytest.raises(ValueError, match=PLAIN):
        ROUTE.to_bytes[0](hm.ActionExecution(1 << 20, "", "move"))  # type: ignore[arg-type]
    wrapper = dds_type(WRAPPED)(execution=cls(type=1), bid=math.inf, has_bid=True)
    with pytest.raises(ValueError, match="bid is inf"):
        next(c for c in ROUTE.channels if c.ros_type == WRAPPED).read(
            wrapper.serialize(use_version_2=False)
        )
