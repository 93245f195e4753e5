"""The mobile-base DBC: typed frames <-> bytes, checked against cantools both ways."""

from __future__ import annotations

import math
from pathlib import Path

import can
import cantools
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from plansys_bridge_adapters.can.dbc import (
    BaseState,
    BaseStatus,
    DbcError,
    EStopCommand,
    FaultBits,
    MalformedFrame,
    MobileBaseDbc,
    OdomPose,
    OdomTwist,
    VelocityCommand,
    default_dbc_path,
)

from plansys_bridge.errors import AdapterError

REPO = Path(__file__).resolve().parents[3]
CONFIG_DBC = REPO / "configs" / "can" / "mobile_base.dbc"

SAMPLES = [
    VelocityCommand(0.5, -0.25, True, 7),
    VelocityCommand(-5.0, 10.0, False, 15),
    EStopCommand(True, 3),
    EStopCommand(False, 0),
    OdomPose(1.234, -5.0, 3.1415),
    OdomPose(-8388.608, 8388.607, -3.1415),
    OdomTwist(0.2, -0.1, 255),
    BaseStatus(87.5, 24.1, FaultBits(motor=True, watchdog=True), BaseState.FAULT, 9),
    BaseStatus(0.0, 0.0, FaultBits(), BaseState.INIT, 0),
]


_DBC = MobileBaseDbc.load()


@pytest.fixture(scope="module")
def dbc() -> MobileBaseDbc:
    return _DBC


@pytest.fixture(scope="module")
def raw_db() -> cantools.database.can.Database:
    db = cantools.database.load_file(str(default_dbc_path()))
    assert isinstance(db, cantools.database.can.Database)
    return db


def test_config_copy_of_dbc_is_the_packaged_one() -> None:
    assert CONFIG_DBC.read_bytes() == default_dbc_path().read_bytes()


def test_ids_sizes_and_priorities(dbc: MobileBaseDbc) -> None:
    ids = {
        t.__name__: dbc.frame_id(t)
        for t in (EStopCommand, VelocityCommand, OdomPose, OdomTwist, BaseStatus)
    }
    assert ids == {
        "EStopCommand": 0x010,
        "VelocityCommand": 0x100,
        "OdomPose": 0x200,
        "OdomTwist": 0x201,
        "BaseStatus": 0x300,
    }
    # The e-stop wins arbitration against everything else.
    assert ids["EStopCommand"] == min(ids.values())
    for t in (EStopCommand, VelocityCommand, OdomPose, OdomTwist, BaseStatus):
        assert dbc.message_for(t).length <= 8
        assert not dbc.message_for(t).is_extended_frame


@pytest.mark.parametrize("frame", SAMPLES, ids=lambda f: type(f).__name__)
def test_typed_frames_match_cantools_in_both_directions(
    frame: object, dbc: MobileBaseDbc, raw_db: cantools.database.can.Database
) -> None:
    msg = dbc.encode(frame)  # type: ignore[arg-type]
    message = raw_db.get_message_by_frame_id(msg.arbitration_id)
    # Our bytes, decoded by plain cantools, give the frame's values...
    signals = message.decode(bytes(msg.data), decode_choices=False)
    assert isinstance(signals, dict)
    # ...plain cantools encoding those values gives our bytes back...
    assert message.encode(signals) == bytes(msg.data)
    # ...and our decoder returns the frame.
    assert dbc.decode(msg) == frame


def test_signal_values_are_where_the_dbc_says(
    raw_db: cantools.database.can.Database, dbc: MobileBaseDbc
) -> None:
    message = raw_db.get_message_by_name("BASE_VelocityCmd")
    data = message.encode({"CmdLinear": 1.5, "CmdAngular": -0.75, "CmdEnable": 1, "CmdCounter": 9})
    # int16 little-endian at 1 mm/s and 1 mrad/s resolution.
    assert data[:2] == (1500).to_bytes(2, "little", signed=True)
    assert data[2:4] == (-750).to_bytes(2, "little", signed=True)
    assert dbc.decode(
        can.Message(arbitration_id=0x100, is_extended_id=False, data=data)
    ) == VelocityCommand(1.5, -0.75, True, 9)


def test_status_state_value_table(raw_db: cantools.database.can.Database) -> None:
    signal = raw_db.get_message_by_name("BASE_Status").get_signal_by_name("BaseState")
    assert signal.choices is not None
    assert {int(k): str(v) for k, v in signal.choices.items()} == {
        s.value: s.name for s in BaseState
    }


def test_yaw_is_normalised_before_encoding(dbc: MobileBaseDbc) -> None:
    decoded = dbc.decode(dbc.encode(OdomPose(0.0, 0.0, 2 * math.pi + 0.5)))
    assert isinstance(decoded, OdomPose)
    assert decoded.yaw == pytest.approx(0.5, abs=1e-4)


def test_counters_wrap(dbc: MobileBaseDbc) -> None:
    assert dbc.decode(dbc.encode(VelocityCommand(0, 0, True, 17))) == VelocityCommand(0, 0, True, 1)
    assert dbc.decode(dbc.encode(OdomTwist(0, 0, 256))) == OdomTwist(0, 0, 0)


def test_out_of_range_command_is_refused(dbc: MobileBaseDbc) -> None:
    with pytest.raises(AdapterError, match="cannot encode BASE_VelocityCmd"):
        dbc.encode(VelocityCommand(6.0, 0.0))


def _std(frame_id: int, data: bytes = b"", *, remote: bool = False) -> can.Message:
    return can.Message(
        arbitration_id=frame_id,
        is_extended_id=False,
        data=data,
        is_remote_frame=remote,
        dlc=8 if remote else None,
    )


@pytest.mark.parametrize(
    ("msg", "kind"),
    [
        (_std(0x7FF, b"\x01"), "unknown_id"),
        (can.Message(arbitration_id=0x200, is_extended_id=True, data=bytes(8)), "unknown_id"),
        (_std(0x200, b"\x01\x02"), "bad_dlc"),
        (_std(0x300, bytes(8)), "bad_dlc"),
        (_std(0x200, remote=True), "remote"),
        (_std(0x300, bytes([0xFF, 0, 0, 0, 0])), "out_of_range"),
        (_std(0x300, bytes([100, 0, 0, 0x0F, 0])), "out_of_range"),
        (_std(0x100, (6000).to_bytes(2, "little") + bytes(3)), "out_of_range"),
    ],
)
def test_malformed_frames_are_classified(msg: can.Message, kind: str, dbc: MobileBaseDbc) -> None:
    with pytest.raises(MalformedFrame) as info:
        dbc.decode(msg)
    assert info.value.kind == kind
    assert f"0x{msg.arbitration_id:03X}" in str(info.value)


def test_dbc_missing_a_signal_is_named(tmp_path: Path) -> None:
    text = default_dbc_path().read_text().replace("PoseYaw", "Heading")
    broken = tmp_path / "broken.dbc"
    broken.write_text(text)
    with pytest.raises(DbcError, match=r"broken\.dbc: BASE_OdomPose has no signal PoseYaw"):
        MobileBaseDbc.load(broken)


def test_missing_dbc_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(DbcError, match=r"nope\.dbc: DBC file not found"):
        MobileBaseDbc.load(tmp_path / "nope.dbc")


def test_dbc_with_other_ids_but_same_names_works(tmp_path: Path) -> None:
    text = default_dbc_path().read_text()
    text = text.replace("BO_ 512 ", "BO_ 1536 ").replace("SG_ 512 ", "SG_ 1536 ")
    other = tmp_path / "other.dbc"
    other.write_text(text)
    dbc = MobileBaseDbc.load(other)
    msg = dbc.encode(OdomPose(1.0, 2.0, 0.5))
    assert msg.arbitration_id == 0x600
    assert dbc.decode(msg) == OdomPose(1.0, 2.0, 0.5)


def _scaled(lo: float, hi: float, scale: float) -> st.SearchStrategy[float]:
    """Values on the signal's grid within its DBC range."""
    return st.integers(math.ceil(lo / scale - 1e-9), math.floor(hi / scale + 1e-9)).map(
        lambda raw: round(raw * scale, 6)
    )


FRAMES = st.one_of(
    st.builds(
        VelocityCommand,
        _scaled(-5, 5, 0.001),
        _scaled(-10, 10, 0.001),
        st.booleans(),
        st.integers(0, 15),
    ),
    st.builds(EStopCommand, st.booleans(), st.integers(0, 15)),
    st.builds(
        OdomPose,
        _scaled(-8388.608, 8388.607, 0.001),
        _scaled(-8388.608, 8388.607, 0.001),
        _scaled(-3.1415, 3.1415, 0.0001),
    ),
    st.builds(
        OdomTwist,
        _scaled(-32.768, 32.767, 0.001),
        _scaled(-32.768, 32.767, 0.001),
        st.integers(0, 255),
    ),
    st.builds(
        BaseStatus,
        _scaled(0, 100, 0.5),
        _scaled(0, 40.95, 0.01),
        st.builds(FaultBits, st.booleans(), st.booleans(), st.booleans(), st.booleans()),
        st.sampled_from(BaseState),
        st.integers(0, 255),
    ),
)


def _close(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, abs_tol=1e-6)
    if type(a) is not type(b):
        return False
    if hasattr(a, "__dataclass_fields__") and not isinstance(a, FaultBits):
        return all(_close(getattr(a, n), getattr(b, n)) for n in a.__dataclass_fields__)
    return a == b


@settings(max_examples=300, deadline=None)
@given(FRAMES)
def test_round_trip_over_signal_ranges(frame: object) -> None:
    dbc = _DBC
    msg = dbc.encode(frame)  # type: ignore[arg-type]
    decoded = dbc.decode(msg)
    assert _close(decoded, frame), (decoded, frame)
    # Bytes -> cantools -> bytes is the identity too.
    message = dbc.database.get_message_by_frame_id(msg.arbitration_id)
    assert message.encode(message.decode(bytes(msg.data), decode_choices=False)) == bytes(msg.data)


@settings(max_examples=300, deadline=None)
@given(
    st.sampled_from([0x010, 0x100, 0x200, 0x201, 0x300, 0x123, 0x7FF]),
    st.binary(max_size=8),
    st.booleans(),
)
def test_any_bytes_decode_or_raise_malformed(frame_id: int, data: bytes, extended: bool) -> None:
    dbc = _DBC
    try:
        frame = dbc.decode(can.Message(arbitration_id=frame_id, is_extended_id=extended, data=data))
    except MalformedFrame:
        return
    # Whatever decodes re-encodes to the same bytes (unused bits aside).
    again = dbc.decode(dbc.encode(frame))
    assert _close(again, frame)
