"""ROS 1 -> ROS 2 bag bridging: streaming conversion into a ROS 2 MCAP bag."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from plansys_bridge_adapters.rosbag.convert import convert_to_ros2, main
from plansys_bridge_adapters.rosbag.errors import BagError, BagTopicError, BagTypeError
from plansys_bridge_adapters.rosbag.reader import BagReader, read_poses
from rosbag_testdata import AMR_LOCATION, HUSKY, real_bag
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Writer1
from rosbags.typesys import Stores, get_types_from_msg, get_typestore


def test_husky_bag_becomes_a_ros2_mcap_bag(tmp_path: Path) -> None:
    dst = tmp_path / "husky"
    report = convert_to_ros2(real_bag(HUSKY[0]), dst, [HUSKY[1], "/fix"])
    assert report.counts == {HUSKY[1]: 3952, "/fix": 989}
    assert [p.suffix for p in dst.iterdir()] and (dst / "husky.mcap").is_file()
    with BagReader(dst) as bag:
        assert not bag.is_ros1
        assert bag.topics == {
            HUSKY[1]: "nav_msgs/msg/Odometry",
            "/fix": "sensor_msgs/msg/NavSatFix",
        }
    # the converted poses are the ones read (and converted) from the ROS 1 bag directly
    assert list(read_poses(dst, HUSKY[1])) == list(read_poses(real_bag(HUSKY[0]), HUSKY[1]))
    with AnyReader([dst]) as reader:
        conn = next(c for c in reader.connections if c.topic == "/fix")
        _, _, raw = next(reader.messages([conn]))
        fix: Any = reader.deserialize(raw, conn.msgtype)
    assert -90 <= fix.latitude <= 90 and not hasattr(fix.header, "seq")


def test_every_topic_by_default(tmp_path: Path) -> None:
    report = convert_to_ros2(real_bag(AMR_LOCATION[0]), tmp_path / "amr")
    assert report.counts[AMR_LOCATION[1]] == 5273
    assert set(report.counts) == {
        "/battery", "/battery_runtime", "/load_perc_available", "/local_plan", "/location",
        "/mode", "/plan", "/troubleshooting/errorcodes", "/velocity",
    }  # fmt: skip
    assert not report.skipped


def _custom_ros1_bag(path: Path) -> None:
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg("float64 level\n", "acme_msgs/msg/Tank"))
    with Writer1(path) as writer:
        tank = writer.add_connection("/tank", "acme_msgs/msg/Tank", typestore=store)
        text = writer.add_connection("/mode", "std_msgs/msg/String", typestore=store)
        writer.write(
            tank,
            10,
            store.serialize_ros1(
                store.types["acme_msgs/msg/Tank"](level=0.5), "acme_msgs/msg/Tank"
            ),
        )
        writer.write(
            text,
            20,
            store.serialize_ros1(
                store.types["std_msgs/msg/String"](data="go"), "std_msgs/msg/String"
            ),
        )


def test_unconvertible_topic_fails_or_is_skipped(tmp_path: Path) -> None:
    src = tmp_path / "custom.bag"
    _custom_ros1_bag(src)
    with pytest.raises(BagTypeError, match="acme_msgs/msg/Tank") as err:
        convert_to_ros2(src, tmp_path / "out")
    assert err.value.topic == "/tank"
    assert not (tmp_path / "out").exists()
    report = convert_to_ros2(src, tmp_path / "out", skip_unconvertible=True)
    assert report.counts == {"/mode": 1}
    assert "unknown to ROS 2 Humble" in report.skipped["/tank"]


def test_errors_leave_no_destination(tmp_path: Path) -> None:
    with pytest.raises(BagTopicError):
        convert_to_ros2(real_bag(HUSKY[0]), tmp_path / "out", ["/nope"])
    assert not (tmp_path / "out").exists()
    data = (real_bag(HUSKY[0])).read_bytes()
    (tmp_path / "cut.bag").write_bytes(data[: len(data) // 2])
    with pytest.raises(BagError, match="truncated or damaged"):
        convert_to_ros2(tmp_path / "cut.bag", tmp_path / "out")
    assert not (tmp_path / "out").exists()
    (tmp_path / "out").mkdir()
    with pytest.raises(BagError, match="exists already"):
        convert_to_ros2(real_bag(HUSKY[0]), tmp_path / "out", [HUSKY[1]])


def test_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "custom.bag"
    _custom_ros1_bag(src)
    assert main([str(src), str(tmp_path / "a")]) == 1
    assert "acme_msgs/msg/Tank" in capsys.readouterr().err
    assert main([str(src), str(tmp_path / "b"), "--skip-unconvertible"]) == 0
    out = capsys.readouterr().out
    assert "/mode: 1 messages" in out and "/tank: skipped" in out
