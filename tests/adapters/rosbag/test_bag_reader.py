"""Reading poses from real ROS 1 and ROS 2 bags, conversion, and located errors."""

from __future__ import annotations

import math
import shutil
import struct
import tracemalloc
from pathlib import Path
from typing import Any

import pytest
from plansys_bridge_adapters.rosbag.errors import (
    BagCorruptError,
    BagError,
    BagTopicError,
    BagTypeError,
)
from plansys_bridge_adapters.rosbag.reader import (
    ODOMETRY,
    POSE_STAMPED,
    POSE_WITH_COVARIANCE_STAMPED,
    BagReader,
    read_poses,
    ros2_typestore,
    yaw_from_quaternion,
)
from rosbag_testdata import AMR_LOCATION, ARDRONE, DEMO_BAGS, HUSKY, NAV2_AMCL, NAV2_ODOM, real_bag
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from plansys_bridge.errors import AdapterError, PlansysBridgeError

# (bag, topic), ROS 2 type, number of messages (SOURCES.md and rosbag info)
REAL = [
    pytest.param(HUSKY, ODOMETRY, 3952, True, id="husky-ros1-odometry"),
    pytest.param(ARDRONE, ODOMETRY, 25217, True, id="ardrone-ros1-odometry"),
    pytest.param(NAV2_ODOM, ODOMETRY, 2639, False, id="nav2-mcap-odom"),
    pytest.param(NAV2_AMCL, POSE_WITH_COVARIANCE_STAMPED, 135, False, id="nav2-mcap-amcl"),
    pytest.param(AMR_LOCATION, POSE_STAMPED, 5273, True, id="amr-ros1-posestamped"),
]


@pytest.mark.parametrize(("source", "msgtype", "count", "ros1"), REAL)
def test_reads_every_pose_of_real_bags(
    source: tuple[str, str], msgtype: str, count: int, ros1: bool
) -> None:
    name, topic = source
    with BagReader(real_bag(name)) as bag:
        assert bag.is_ros1 is ros1
        assert bag.topics[topic] == msgtype
        assert bag.message_count(topic) == count
        n = 0
        last_time = -1
        for sample in bag.poses(topic):
            assert sample.msgtype == msgtype
            assert bag.start_ns <= sample.bag_time_ns <= bag.end_ns
            assert sample.bag_time_ns >= last_time
            last_time = sample.bag_time_ns
            assert all(math.isfinite(v) for v in (sample.x, sample.y, sample.z, sample.yaw))
            n += 1
    assert n == count


@pytest.mark.parametrize(
    "source", [HUSKY, ARDRONE, AMR_LOCATION], ids=["husky", "ardrone", "amr-location"]
)
def test_ros1_messages_become_ros2_messages(source: tuple[str, str]) -> None:
    """The CDR bytes decode with ROS 2 Humble types and keep every value but ``seq``."""
    name, topic = source
    path = real_bag(name)
    with AnyReader([path]) as ros1:
        conn = next(c for c in ros1.connections if c.topic == topic)
        originals: list[Any] = []
        for _, _, raw in ros1.messages([conn]):
            originals.append(ros1.deserialize(raw, conn.msgtype))
            if len(originals) == 50:
                break
    samples = []
    for sample in read_poses(path, topic):
        samples.append(sample)
        if len(samples) == 50:
            break
    for original, sample in zip(originals, samples, strict=True):
        msg = sample.message()
        assert type(msg).__name__ == type(original).__name__
        assert not hasattr(msg.header, "seq") and hasattr(original.header, "seq")
        assert msg.header.stamp.sec == original.header.stamp.sec
        assert msg.header.stamp.nanosec == original.header.stamp.nanosec
        assert msg.header.frame_id == original.header.frame_id == sample.frame_id
        pose = original.pose if sample.msgtype == POSE_STAMPED else original.pose.pose
        assert (sample.x, sample.y, sample.z) == (
            pose.position.x,
            pose.position.y,
            pose.position.z,
        )
        assert ros2_typestore().serialize_cdr(msg, sample.msgtype) == sample.cdr


def test_husky_odometry_values() -> None:
    """Spot values: the Husky starts 8.25 m along x in its odom frame and drives away."""
    first = next(read_poses(real_bag(HUSKY[0]), HUSKY[1]))
    assert first.frame_id == "odom"
    assert first.x == pytest.approx(8.2515628, abs=1e-6)
    assert first.y == pytest.approx(-0.3048932, abs=1e-6)
    assert first.stamp == pytest.approx(1432235498.027976, abs=1e-6)


def test_time_window_selects_messages() -> None:
    with BagReader(real_bag(NAV2_ODOM[0])) as bag:
        start = bag.start_ns + 10 * 10**9
        stop = bag.start_ns + 20 * 10**9
        window = list(bag.poses(NAV2_ODOM[1], start, stop))
        assert window
        assert all(start <= s.bag_time_ns < stop for s in window)
        assert len(window) < bag.message_count(NAV2_ODOM[1]) / 5


def test_missing_topic_names_bag_and_topics() -> None:
    path = real_bag(HUSKY[0])
    with BagReader(path) as bag, pytest.raises(BagTopicError) as err:
        list(bag.poses("/odom"))
    text = str(err.value)
    assert str(path) in text and "/odom" in text and "/husky_velocity_controller/odom" in text
    assert err.value.topic == "/odom"
    assert isinstance(err.value, AdapterError)


def test_type_without_pose_is_refused() -> None:
    with BagReader(real_bag(HUSKY[0])) as bag, pytest.raises(BagTypeError) as err:
        next(bag.poses("/imu/data"))
    assert "sensor_msgs/msg/Imu" in str(err.value) and "/imu/data" in str(err.value)


def test_message_type_unknown_to_ros2(tmp_path: Path) -> None:
    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg("float64 x\nfloat64 y\n", "acme_msgs/msg/Spot"))
    path = tmp_path / "custom"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/spot", "acme_msgs/msg/Spot", typestore=store)
        msg = store.types["acme_msgs/msg/Spot"](x=1.0, y=2.0)
        writer.write(conn, 5, store.serialize_cdr(msg, "acme_msgs/msg/Spot"))
    with BagReader(path) as bag, pytest.raises(BagTypeError) as err:
        next(bag.messages("/spot"))
    assert "acme_msgs/msg/Spot" in str(err.value) and "/spot" in str(err.value)


def test_missing_file_and_unknown_format(tmp_path: Path) -> None:
    with pytest.raises(BagError, match="not found"):
        BagReader(tmp_path / "nothing.bag").open()
    other = tmp_path / "poses.csv"
    other.write_text("x,y\n")
    with pytest.raises(BagError, match="unknown bag format"):
        BagReader(other).open()


@pytest.mark.parametrize(
    ("name", "topic"), [HUSKY, ARDRONE, NAV2_ODOM, AMR_LOCATION], ids=lambda v: str(v)
)
@pytest.mark.parametrize("fraction", [0.2, 0.9])
def test_truncated_copies_fail_clearly(
    tmp_path: Path, name: str, topic: str, fraction: float
) -> None:
    data = (real_bag(name)).read_bytes()
    copy = tmp_path / name
    copy.write_bytes(data[: int(len(data) * fraction)])
    with pytest.raises(BagCorruptError) as err, BagReader(copy) as bag:
        for _ in bag.poses(topic):
            pass
    assert str(copy) in str(err.value)
    assert "truncated or damaged" in str(err.value)
    assert isinstance(err.value.__cause__, Exception)


@pytest.mark.parametrize(
    ("name", "topic", "fraction"),
    [(*HUSKY, 0.5), (*AMR_LOCATION, 0.3), (*NAV2_ODOM, 0.3)],
    ids=["husky-bz2-chunk", "amr-record-header", "nav2-zstd-chunk"],
)
def test_damaged_middle_fails_with_topic_and_last_good_time(
    tmp_path: Path, name: str, topic: str, fraction: float
) -> None:
    data = bytearray((real_bag(name)).read_bytes())
    at = int(len(data) * fraction)
    data[at : at + 4000] = b"\xff" * 4000
    copy = tmp_path / name
    copy.write_bytes(bytes(data))
    seen: list[int] = []
    with pytest.raises(BagCorruptError) as err, BagReader(copy) as bag:
        for sample in bag.poses(topic):
            seen.append(sample.bag_time_ns)
    assert err.value.topic == topic
    assert err.value.timestamp == (seen[-1] if seen else None)
    assert str(copy) in str(err.value)


@pytest.mark.parametrize("length", [2**64 - 1, 2**62], ids=["overflow", "memory"])
def test_absurd_mcap_record_length_fails_clearly(tmp_path: Path, length: int) -> None:
    """A damaged uint64 record length in the mcap summary is corruption, not a crash."""
    data = bytearray((real_bag(NAV2_ODOM[0])).read_bytes())
    (summary_start,) = struct.unpack_from("<Q", data, len(data) - 37 + 9)
    assert summary_start, "the test bag has a summary section"
    struct.pack_into("<Q", data, summary_start + 1, length)  # after the record's opcode
    copy = tmp_path / NAV2_ODOM[0]
    copy.write_bytes(bytes(data))
    with pytest.raises(BagCorruptError) as err, BagReader(copy) as bag:
        for _ in bag.poses(NAV2_ODOM[1]):
            pass
    assert str(copy) in str(err.value)


def test_errors_are_project_errors() -> None:
    err = BagCorruptError("broken", "/x.bag", "/odom", 1_500_000_000)
    assert isinstance(err, PlansysBridgeError)
    assert str(err) == "/x.bag topic /odom at t=1500000000 ns (1.500 s): broken"


def test_yaw_from_quaternion() -> None:
    half = math.radians(30) / 2
    assert yaw_from_quaternion(0.0, 0.0, math.sin(half), math.cos(half)) == pytest.approx(
        math.radians(30)
    )
    assert yaw_from_quaternion(0.0, 0.0, 1.0, 0.0) == pytest.approx(math.pi)


def test_reading_streams_instead_of_loading(tmp_path: Path) -> None:
    """A 14 MB bag is read with a few MB of memory: one chunk at a time."""
    store = ros2_typestore()
    sample_bag = DEMO_BAGS / "kitchen_nav"
    first = next(read_poses(sample_bag, "/odom"))
    path = tmp_path / "big"
    count = 20_000
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/odom", ODOMETRY, typestore=store)
        for i in range(count):
            writer.write(conn, 1_000_000 + i * 10_000_000, first.cdr)
    total = count * len(first.cdr)
    assert total > 10e6
    tracemalloc.start()
    try:
        n = sum(1 for _ in read_poses(path, "/odom"))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
        shutil.rmtree(path)
    assert n == count
    assert peak < total / 4, f"peak {peak / 1e6:.1f} MB for {total / 1e6:.1f} MB of messages"


def test_ros1_definition_that_differs_from_ros2_is_refused(tmp_path: Path) -> None:
    """A ROS 1 bag whose PoseStamped is not the standard one cannot be converted."""
    store = get_typestore(Stores.EMPTY)
    store.register(
        get_types_from_msg("uint32 seq\ntime stamp\nstring frame_id\n", "std_msgs/msg/Header")
    )
    store.register(
        get_types_from_msg("std_msgs/Header header\nfloat64 x\nfloat64 y\n", POSE_STAMPED)
    )
    types = store.types
    path = tmp_path / "odd.bag"
    with Writer1(path) as writer:
        conn = writer.add_connection("/pose", POSE_STAMPED, typestore=store)
        header = types["std_msgs/msg/Header"](
            seq=1, stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="m"
        )
        msg = types[POSE_STAMPED](header=header, x=1.0, y=2.0)
        writer.write(conn, 1000, store.serialize_ros1(msg, POSE_STAMPED))
    with pytest.raises(BagTypeError, match="differs from ROS 2 Humble's") as err:
        list(read_poses(path, "/pose"))
    assert err.value.topic == "/pose" and str(path) in str(err.value)


@pytest.mark.parametrize("bare_file", [False, True], ids=["rosbag2-dir", "bare-db3"])
def test_ros2_sqlite3_bags(demo_bags: Path, tmp_path: Path, bare_file: bool) -> None:
    """The same drive copied into a ROS 2 sqlite3 bag reads back identically."""
    store = ros2_typestore()
    path = tmp_path / "kitchen_db3"
    with (
        AnyReader([demo_bags / "kitchen_nav"]) as src,
        Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3) as dst,
    ):
        conns = {
            c.id: dst.add_connection(c.topic, c.msgtype, typestore=store) for c in src.connections
        }
        for conn, t, raw in src.messages():
            dst.write(conns[conn.id], t, raw)
    [db3] = path.glob("*.db3")
    target = db3 if bare_file else path
    expected = list(read_poses(demo_bags / "kitchen_nav", "/amcl_pose"))
    assert list(read_poses(target, "/amcl_pose")) == expected
    assert len(expected) == 149


def test_ros1_poses_read_from_the_front_equal_the_fully_decoded_message() -> None:
    """ROS 1 poses are read without decoding the whole message: same stamp, frame,
    pose and CDR bytes as rosbags' full decoding gives."""
    from plansys_bridge_adapters.rosbag.reader import pose_from_message, ros2_typestore

    repo = Path(__file__).resolve().parents[3]
    for path, topic in (
        (repo / "bags" / "kitchen_nav_ros1.bag", "/robot_pose"),
        (repo / "tests" / "fixtures" / "bags" / "rl_test1.bag", "/husky_velocity_controller/odom"),
    ):
        if not path.is_file():
            continue
        with BagReader(path) as bag:
            poses = list(bag.poses(topic))
            raws = list(bag.messages(topic))
        assert len(poses) == len(raws) > 0
        store = ros2_typestore()
        for sample, raw in zip(poses[:300], raws[:300], strict=False):
            full = pose_from_message(
                store.deserialize_cdr(raw.cdr, raw.msgtype), raw.msgtype, raw.bag_time_ns, raw.cdr
            )
            assert sample == full
            assert sample.cdr == raw.cdr


def test_a_truncated_ros1_pose_is_a_corrupt_bag_error() -> None:
    from plansys_bridge_adapters.rosbag.ros1_pose import ros1_pose

    header = struct.pack("<III", 7, 100, 500) + struct.pack("<I", 3) + b"map"
    pose = struct.pack("<7d", 1, 2, 3, 0, 0, 0, 1)
    assert ros1_pose(header + pose, odometry=False) == (100.0000005, "map", (1, 2, 3, 0, 0, 0, 1))
    with pytest.raises(struct.error):
        ros1_pose(header + pose[:20], odometry=False)
    with pytest.raises(struct.error):
        ros1_pose(header[:14], odometry=False)
