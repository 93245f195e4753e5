"""The vehicle double as a ground station sees it, through pymavlink's own client side
(``mavutil`` as MAVProxy uses it: ``param_fetch_all``, ``mavparm.mavset``): the full
parameter list, reads and writes, stream rates and AUTOPILOT_VERSION, answered as
ArduPilot answers them. Where ``PLANSYS_BRIDGE_SITL_DIR`` names ArduPilot SITL, the same
probe runs against real ArduCopter and both answers must agree.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from typing import Any

import pytest
from plansys_bridge_adapters.mavlink.double import VehicleDouble
from pymavlink import mavparm, mavutil
from pymavlink.dialects.v20 import ardupilotmega as ml
from sitl_support import Sitl

GCS = 250
NO_INDEX = 65535
"""param_index -1 as the uint16 on the wire."""


@pytest.fixture
def gcs_link() -> Iterator[tuple[VehicleDouble, Any]]:
    # 2x: simulation steps stay short, so stream timing stays close to the rate asked
    with VehicleDouble("copter", speedup=2, ekf_delay=2.0) as double:
        link = mavutil.mavlink_connection(double.url, source_system=GCS, source_component=190)
        try:
            link.wait_heartbeat(timeout=10)
            yield double, link
        finally:
            link.close()


def _param(link: Any, name: str, timeout: float = 3.0) -> Any | None:
    """The next PARAM_VALUE naming ``name`` (others are skipped), or None."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = link.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.2)
        if msg is not None and msg.param_id == name:
            return msg
    return None


def fetch_all(
    link: Any, timeout: float = 30.0
) -> tuple[dict[int, tuple[str, float, int]], list[str]]:
    """``param_fetch_all`` and every PARAM_VALUE until each index of the count came."""
    link.param_fetch_all()
    seen: dict[int, tuple[str, float, int]] = {}
    texts: list[str] = []
    count = None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and (count is None or len(seen) < count):
        msg = link.recv_match(type=["PARAM_VALUE", "STATUSTEXT"], blocking=True, timeout=0.5)
        if msg is None:
            continue
        if msg.get_type() == "STATUSTEXT":
            texts.append(msg.text)
        elif msg.param_index != NO_INDEX:
            count = msg.param_count
            seen[msg.param_index] = (msg.param_id, msg.param_value, msg.param_type)
    assert count is not None and len(seen) == count, f"{len(seen)} of {count} parameters"
    return seen, texts


def probe(link: Any) -> dict[str, Any]:
    """What an ArduPilot ground station relies on, in a form two vehicles can be
    compared by."""
    out: dict[str, Any] = {}
    hb = link.wait_heartbeat(timeout=10)
    out["heartbeat_from"] = (hb.get_srcSystem(), hb.get_srcComponent())
    link.mav.param_request_read_send(1, 1, b"RTL_ALT", -1)
    by_name = _param(link, "RTL_ALT")
    out["read_by_name"] = (by_name.param_type, by_name.param_index)
    link.mav.param_request_read_send(1, 1, b"NO_SUCH_PARAM", -1)
    out["read_unknown"] = _param(link, "NO_SUCH_PARAM", 1.0)
    link.mav.param_request_read_send(1, 1, b"", 5000)
    out["read_bad_index"] = link.recv_match(type="PARAM_VALUE", blocking=True, timeout=1.0)
    # writes: truncation toward zero, clamping to the type, the parameter's own type
    sets = [
        ("RTL_ALT", 2000.7, ml.MAV_PARAM_TYPE_INT32),
        ("RTL_ALT", -1999.6, ml.MAV_PARAM_TYPE_INT32),
        ("FLTMODE6", 300.0, ml.MAV_PARAM_TYPE_INT8),
        ("FLTMODE6", -3.6, ml.MAV_PARAM_TYPE_INT8),
        ("WPNAV_SPEED", 750.0, ml.MAV_PARAM_TYPE_INT8),
    ]
    echoes = []
    for name, value, kind in sets:
        link.mav.param_set_send(1, 1, name.encode(), value, kind)
        echo = _param(link, name)
        assert echo is not None, f"no echo of {name}"
        echoes.append((echo.param_value, echo.param_type, echo.param_index))
    out["set_echoes"] = echoes
    link.mav.param_set_send(1, 1, b"RTL_ALT", math.nan, ml.MAV_PARAM_TYPE_INT32)
    out["set_nan"] = _param(link, "RTL_ALT", 1.0)
    link.mav.param_set_send(1, 1, b"NO_SUCH_PARAM", 1.0, ml.MAV_PARAM_TYPE_REAL32)
    out["set_unknown"] = _param(link, "NO_SUCH_PARAM", 1.0)
    # AUTOPILOT_VERSION, after the ACK, both ways of asking
    for command, p1 in (
        (ml.MAV_CMD_REQUEST_MESSAGE, ml.MAVLINK_MSG_ID_AUTOPILOT_VERSION),
        (ml.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1),
    ):
        link.mav.command_long_send(1, 1, command, 0, p1, 0, 0, 0, 0, 0, 0)
        order = []
        version = None
        deadline = time.monotonic() + 5
        while version is None and time.monotonic() < deadline:
            msg = link.recv_match(
                type=["COMMAND_ACK", "AUTOPILOT_VERSION"], blocking=True, timeout=1
            )
            if msg is None or (msg.get_type() == "COMMAND_ACK" and msg.command != command):
                continue
            order.append(msg.get_type())
            if msg.get_type() == "AUTOPILOT_VERSION":
                version = msg
        assert version is not None, f"no AUTOPILOT_VERSION for {command}: {order}"
        out[f"version_{command}"] = (order, version.capabilities, version.flight_sw_version & 0xFF)
    return out


def test_heartbeat_from_the_autopilot_component(gcs_link: tuple[VehicleDouble, Any]) -> None:
    _double, link = gcs_link
    hb = link.wait_heartbeat(timeout=5)
    assert (hb.get_srcSystem(), hb.get_srcComponent()) == (1, ml.MAV_COMP_ID_AUTOPILOT1)
    assert hb.autopilot == ml.MAV_AUTOPILOT_ARDUPILOTMEGA


def test_param_fetch_all_gets_the_full_list(gcs_link: tuple[VehicleDouble, Any]) -> None:
    double, link = gcs_link
    seen, texts = fetch_all(link)
    names = [seen[i][0] for i in sorted(seen)]
    assert sorted(seen) == list(range(len(seen)))
    assert len(set(names)) == len(names) == len(double.sim.gcs.params)
    assert {"SYSID_THISMAV", "RTL_ALT", "WPNAV_SPEED", "SR0_POSITION"} <= set(names)
    assert any(t.startswith("ArduCopter V") for t in texts)  # the banner, as ArduPilot
    # mavutil keeps what it heard, as MAVProxy's param list shows it
    assert link.params["RTL_ALT"] == pytest.approx(double.sim.p.rtl_alt * 100)
    types = {name: kind for name, _value, kind in seen.values()}
    assert types["RTL_ALT"] == ml.MAV_PARAM_TYPE_INT32
    assert types["FLTMODE6"] == ml.MAV_PARAM_TYPE_INT8
    assert types["WPNAV_SPEED"] == ml.MAV_PARAM_TYPE_REAL32


def test_answers_as_ardupilot_answers(gcs_link: tuple[VehicleDouble, Any]) -> None:
    _double, link = gcs_link
    answers = probe(link)
    assert answers == EXPECTED, answers


EXPECTED: dict[str, Any] = {
    "heartbeat_from": (1, 1),
    "read_by_name": (ml.MAV_PARAM_TYPE_INT32, NO_INDEX),
    "read_unknown": None,
    "read_bad_index": None,
    "set_echoes": [
        (2000.0, ml.MAV_PARAM_TYPE_INT32, NO_INDEX),
        (-1999.0, ml.MAV_PARAM_TYPE_INT32, NO_INDEX),
        (127.0, ml.MAV_PARAM_TYPE_INT8, NO_INDEX),
        (-3.0, ml.MAV_PARAM_TYPE_INT8, NO_INDEX),
        (750.0, ml.MAV_PARAM_TYPE_REAL32, NO_INDEX),
    ],
    "set_nan": None,
    "set_unknown": None,
    f"version_{ml.MAV_CMD_REQUEST_MESSAGE}": (["COMMAND_ACK", "AUTOPILOT_VERSION"], 64495, 255),
    f"version_{ml.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES}": (
        ["COMMAND_ACK", "AUTOPILOT_VERSION"],
        64495,
        255,
    ),
}
"""What ArduCopter 4.6.3 SITL answers to :func:`probe` (the sitl test checks it)."""


def test_read_by_index_names_the_parameter(gcs_link: tuple[VehicleDouble, Any]) -> None:
    double, link = gcs_link
    index = double.sim.gcs.params.index_of("RTL_ALT")
    link.mav.param_request_read_send(1, 1, b"", index)
    msg = _param(link, "RTL_ALT")
    assert msg is not None and msg.param_index == index


def test_written_parameters_change_the_vehicle(gcs_link: tuple[VehicleDouble, Any]) -> None:
    double, link = gcs_link
    params = mavparm.MAVParmDict()
    # MAVProxy's `param set`: PARAM_SET, then wait for the echo (retrying)
    assert params.mavset(link, "RTL_ALT", 3000)
    assert params.mavset(link, "WPNAV_SPEED", 450)
    assert params.mavset(link, "DISARM_DELAY", 4)
    assert double.sim.p.rtl_alt == pytest.approx(30.0)
    assert double.sim.p.cruise_speed == pytest.approx(4.5)
    assert double.sim.p.disarm_delay == pytest.approx(4.0)


def _period(link: Any, kind: str, count: int = 9) -> float:
    """Mean seconds of vehicle time between ``count`` consecutive ``kind`` messages.

    A message goes out on the first simulation step at or after its due time, so
    each gap may overrun by up to one step (more on a loaded machine): the mean over
    several says whether the rate asked for is the one sent."""
    stamps: list[float] = []
    deadline = time.monotonic() + 20
    while len(stamps) < count and time.monotonic() < deadline:
        msg = link.recv_match(type=kind, blocking=True, timeout=1)
        if msg is not None:
            stamps.append(msg.time_boot_ms / 1000)
    assert len(stamps) == count, f"{len(stamps)} {kind} in 20 s"
    return (stamps[-1] - stamps[0]) / (count - 1)


def test_request_data_stream_sets_the_rate_and_its_parameter(
    gcs_link: tuple[VehicleDouble, Any],
) -> None:
    double, link = gcs_link
    link.mav.request_data_stream_send(1, 1, ml.MAV_DATA_STREAM_POSITION, 4, 1)
    period = _period(link, "GLOBAL_POSITION_INT")
    assert 0.24 <= period <= 0.32, period  # 4 Hz of vehicle time
    link.mav.param_request_read_send(1, 1, b"SR0_POSITION", -1)
    assert _param(link, "SR0_POSITION").param_value == 4.0
    link.mav.request_data_stream_send(1, 1, ml.MAV_DATA_STREAM_POSITION, 4, 0)  # stop
    time.sleep(0.3)
    link.recv_match(type="GLOBAL_POSITION_INT", blocking=False)
    while link.recv_match(blocking=False) is not None:
        pass
    assert link.recv_match(type="GLOBAL_POSITION_INT", blocking=True, timeout=1.0) is None
    link.mav.request_data_stream_send(1, 1, ml.MAV_DATA_STREAM_ALL, 2, 1)
    for kind in ("SYS_STATUS", "GPS_RAW_INT", "ATTITUDE", "VFR_HUD", "BATTERY_STATUS"):
        assert link.recv_match(type=kind, blocking=True, timeout=3) is not None, kind
    assert double.sim.gcs.params.get("SR0_PARAMS").value == 0.0  # ALL leaves it alone


def test_set_message_interval_rate_is_honoured(gcs_link: tuple[VehicleDouble, Any]) -> None:
    _double, link = gcs_link
    link.mav.command_long_send(
        1, 1, ml.MAV_CMD_SET_MESSAGE_INTERVAL, 0, ml.MAVLINK_MSG_ID_ATTITUDE, 100_000, 0, 0, 0, 0, 0
    )
    period = _period(link, "ATTITUDE")
    assert 0.095 <= period <= 0.2, period  # 10 Hz of vehicle time (not the 4 Hz default)


@pytest.mark.sitl
def test_sitl_answers_the_same(sitl: Sitl) -> None:
    copter = sitl.start("copter", speedup=10.0)
    link = mavutil.mavlink_connection(copter.url, source_system=GCS, source_component=190)
    try:
        link.wait_heartbeat(timeout=60)
        time.sleep(3)  # SITL announces some parameters of its own while it boots
        answers = probe(link)
        seen, _texts = fetch_all(link)
    finally:
        link.close()
    assert answers == EXPECTED, answers
    with VehicleDouble("copter", speedup=10, ekf_delay=2.0) as double:
        ours = {p.name: p.type for p in double.sim.gcs.params}
    theirs = {name: kind for name, _value, kind in seen.values()}
    assert set(ours) <= set(theirs), sorted(set(ours) - set(theirs))
    assert {n: theirs[n] for n in ours} == ours


@pytest.mark.sitl
def test_rover_parameters_exist_in_sitl_with_their_types(sitl: Sitl) -> None:
    rover = sitl.start("rover", speedup=10.0)
    link = mavutil.mavlink_connection(rover.url, source_system=GCS, source_component=190)
    try:
        link.wait_heartbeat(timeout=60)
        seen, texts = fetch_all(link)
    finally:
        link.close()
    assert any(t.startswith("ArduRover V") for t in texts)
    with VehicleDouble("rover", speedup=10, ekf_delay=2.0) as double:
        ours = {p.name: p.type for p in double.sim.gcs.params}
    theirs = {name: kind for name, _value, kind in seen.values()}
    assert set(ours) <= set(theirs), sorted(set(ours) - set(theirs))
    assert {n: theirs[n] for n in ours} == ours


def test_rover_list_and_its_bound_speed() -> None:
    with VehicleDouble("rover", speedup=10, ekf_delay=2.0) as double:
        link = mavutil.mavlink_connection(double.url, source_system=GCS, source_component=190)
        try:
            hb = link.wait_heartbeat(timeout=10)
            assert (hb.get_srcComponent(), hb.type) == (1, ml.MAV_TYPE_GROUND_ROVER)
            seen, texts = fetch_all(link)
            assert any(t.startswith("ArduRover V") for t in texts)
            assert len(seen) == len(double.sim.gcs.params)
            assert mavparm.MAVParmDict().mavset(link, "WP_SPEED", 3.5)
        finally:
            link.close()
        assert double.sim.p.cruise_speed == pytest.approx(3.5)
