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


def test_a_kept_rest_is_used_only_at_the_same_remainder_modulo_8() -> None:
    """Node names 4 bytes apart in length move the rest by 4: the padding before the
    bid differs, so the same rest bytes must not be taken for the other's."""
    read = next(c for c in ROUTE.channels if c.ros_type == WRAPPED).read
    to_wrapped = ROUTE.to_bytes[1]
    assert to_wrapped is not None
    for request_id in ("", "r", "rq", "req", "req-", "req-1", "req-12", "req-123"):
        sent = [
            hm.ActionExecution(
                hm.ExecutionType.RESPONSE, node, "move", ("r", "a"), bid=bid, request_id=request_id
            )
            for node in ("p1", "p1234", "p1", "p12345678")
            for bid in (None, 2.5)
        ]
        for msg in sent * 2:
            data = to_wrapped(msg)
            assert read(data) == msg == _generic_read(WRAPPED, data)
        # A rest kept at one remainder, after a node name 4 bytes longer: to the
        # generated reader the bid is elsewhere (or past the end).
        short = to_wrapped(sent[1])  # node "p1": the rest starts at byte 16
        moved = to_wrapped(sent[2])[:20] + short[16:]  # node "p1234": at byte 20
        read(short)
        try:
            expected = _generic_read(WRAPPED, moved)
        except ValueError:
            with pytest.raises(ValueError):
                read(moved)
        else:
            assert read(moved) == expected


def test_bytes_after_a_samples_end_are_ignored_and_not_kept() -> None:
    """As the generated reader: what follows the last field does not change the message."""
    for channel, write in zip(ROUTE.channels, ROUTE.to_bytes, strict=True):
        assert write is not None
        msg = hm.ActionExecution(
            hm.ExecutionType.RESPONSE, "p7", "move", ("r",), bid=1.5, request_id="q"
        )
        data = write(msg)
        for extra in (b"\x00" * 4, b"\x01" * 8, b"\x02" * 12):
            for _twice in range(2):
                longer = data + extra
                assert channel.read(longer) == _generic_read(channel.ros_type, longer)
                assert channel.read(data) == _generic_read(channel.ros_type, data)


def test_a_kept_front_is_only_the_front() -> None:
    """Bytes that start like a sample read before are still read to their end: a
    truncated sample is refused, and another type or node name is not taken for it."""
    read = next(c for c in ROUTE.channels if c.ros_type == WRAPPED).read
    to_wrapped = ROUTE.to_bytes[1]
    assert to_wrapped is not None
    msg = hm.ActionExecution(hm.ExecutionType.RESPONSE, "p17", "move", ("r",), bid=2.0)
    data = to_wrapped(msg)
    assert read(data) == msg  # its front is kept now
    for cut in (16, 20, len(data) - 1):
        with pytest.raises(ValueError, match=r"malformed sample|past the end"):
            read(data[:cut])
    for other in (
        hm.ActionExecution(hm.ExecutionType.REJECT, "p17", "move", ("r",)),
        hm.ActionExecution(hm.ExecutionType.RESPONSE, "p18", "move", ("r",), bid=2.0),
    ):
        assert read(to_wrapped(other)) == other
