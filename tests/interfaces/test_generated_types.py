"""Every generated type (rosbags typestore, Cyclone DDS) against its vendored .msg text.

The .msg texts are read here with a parser of this test's own (ROS 2's interface
rules: comments, constants, ``T[]``, ``T[N]``, ``T[<=N]``, ``string<=N``, relative
names meaning the same package's ``msg``), so the generator is checked against the
text, not against itself.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")
pytest.importorskip("rosbags", reason="rosbags (extra 'rosbag') is not installed")

from cyclonedds.idl import types as t

import plansys_bridge.interfaces as interfaces
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.interfaces.definitions import ros2_definitions
from plansys_bridge.interfaces.typestore import mcap_schema, ros2_typestore

ROOT = Path(interfaces.__file__).parent / "ros2"

# rosidl_adapter's MSG_TYPE_TO_IDL, as Cyclone's Python types.
IDL: dict[str, Any] = {
    "bool": bool,
    "byte": t.byte,
    "char": t.uint8,
    "int8": t.int8,
    "uint8": t.uint8,
    "int16": t.int16,
    "uint16": t.uint16,
    "int32": t.int32,
    "uint32": t.uint32,
    "int64": t.int64,
    "uint64": t.uint64,
    "float32": t.float32,
    "float64": t.float64,
    "string": str,
}
CONSTANT = re.compile(r"^\S+\s+[A-Za-z_]\w*\s*=")
ARRAY = re.compile(r"^(?P<base>[^\[]+)\[(?P<bound><=)?(?P<size>\d*)\]$")


def interface_files() -> list[Path]:
    return sorted(p for p in ROOT.glob("*/*/*") if p.suffix in (".msg", ".srv", ".action"))


def parts(path: Path) -> dict[str, str]:
    """Type name -> .msg text of each part of one interface file."""
    pkg, kind, name = path.parent.parent.name, path.parent.name, path.stem
    chunks = re.split(r"(?m)^---\s*$", path.read_text(encoding="utf-8"))
    suffixes = {"msg": [""], "srv": ["_Request", "_Response"]}.get(
        kind, ["_Goal", "_Result", "_Feedback"]
    )
    assert len(chunks) == len(suffixes), path
    return {f"{pkg}/{kind}/{name}{s}": c for s, c in zip(suffixes, chunks, strict=True)}


def fields(text: str) -> list[tuple[str, str]]:
    found = []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line or CONSTANT.match(line):
            continue
        type_text, name = line.split()[:2]
        found.append((name, type_text))
    return found


def resolve(pkg: str, name: str) -> str:
    if "/" not in name:
        return f"{pkg}/msg/{name}"
    head, tail = name.split("/", 1)
    return f"{head}/msg/{tail}" if "/" not in tail else name


def expected_idl(pkg: str, type_text: str) -> Any:
    array = ARRAY.match(type_text)
    if array is not None:
        element = expected_idl(pkg, array["base"])
        if array["size"] and not array["bound"]:
            return t.array[element, int(array["size"])]
        return t.sequence[element, int(array["size"])] if array["size"] else t.sequence[element]
    if type_text.startswith("string<="):
        return t.bounded_str[int(type_text[len("string<=") :])]
    if type_text in IDL:
        return IDL[type_text]
    nested = resolve(pkg, type_text)
    cls = dds_type(nested)
    p, k, n = nested.split("/")
    assert cls.__idl_typename__ == f"{p}::{k}::dds_::{n}_"
    return cls


def all_parts() -> list[tuple[str, str]]:
    return [(name, text) for path in interface_files() for name, text in parts(path).items()]


@pytest.mark.parametrize(("name", "text"), all_parts(), ids=lambda v: v if "/" in v else "")
def test_dds_type_matches_the_msg_text(name: str, text: str) -> None:
    pkg, kind, base = name.split("/")
    cls = dds_type(name)
    assert cls.__idl_typename__ == f"{pkg}::{kind}::dds_::{base}_"
    want = [(n, expected_idl(pkg, ty)) for n, ty in fields(text)]
    if not want:  # rosidl's member of an empty message
        want = [("structure_needs_at_least_one_member", t.uint8)]
    assert list(cls.__annotations__.items()) == want
    cls().serialize()  # every generated type has a serialisable zero value


@pytest.mark.parametrize(("name", "text"), all_parts(), ids=lambda v: v if "/" in v else "")
def test_typestore_entry_matches_the_msg_text(name: str, text: str) -> None:
    pkg = name.split("/")[0]
    store = ros2_typestore()
    got = [(n, d) for n, d in store.fielddefs[name][1]]
    want = fields(text) or [("structure_needs_at_least_one_member", "uint8")]
    assert [n for n, _ in got] == [n for n, _ in want]
    for (fname, desc), (_, type_text) in zip(got, want, strict=True):
        assert describe(desc) == normalise(pkg, type_text), f"{name}.{fname}"


def describe(desc: tuple[Any, Any]) -> str:
    kind, detail = desc
    if kind == 1:
        base, bound = detail
        return f"{base}<={bound}" if bound else base
    if kind == 2:
        return str(detail)
    inner, size = detail
    return f"{describe(inner)}[{size if kind == 3 else ('<=' + str(size) if size else '')}]"


def normalise(pkg: str, type_text: str) -> str:
    array = ARRAY.match(type_text)
    if array is not None:
        bound = ("<=" if array["bound"] else "") + array["size"]
        return f"{normalise(pkg, array['base'])}[{bound}]"
    if type_text in IDL or type_text.startswith("string<="):
        return type_text
    return resolve(pkg, type_text)


def test_every_file_is_generated_and_every_package_names_its_origin() -> None:
    definitions = ros2_definitions()
    for name, _text in all_parts():
        assert name in definitions
    for pkg in (p for p in ROOT.iterdir() if p.is_dir()):
        source = (pkg / "SOURCE.md").read_text(encoding="utf-8")
        assert "licen" in source.lower(), pkg
        if pkg.name != "plansys_bridge_msgs":
            assert "repository: https://github.com/" in source, pkg
            assert re.search(r"commit: `[0-9a-f]{40}`", source), pkg
            assert (pkg / "LICENSE").is_file(), pkg


def test_action_wire_messages_follow_rosidl() -> None:
    base = "nav2_msgs/action/NavigateToPose"
    names = {
        suffix: list(dds_type(base + suffix).__annotations__)
        for suffix in (
            "_SendGoal_Request",
            "_SendGoal_Response",
            "_GetResult_Request",
            "_GetResult_Response",
            "_FeedbackMessage",
        )
    }
    assert names == {
        "_SendGoal_Request": ["goal_id", "goal"],
        "_SendGoal_Response": ["accepted", "stamp"],
        "_GetResult_Request": ["goal_id"],
        "_GetResult_Response": ["status", "result"],
        "_FeedbackMessage": ["goal_id", "feedback"],
    }
    uuid = dds_type(base + "_SendGoal_Request").__annotations__["goal_id"]
    assert uuid.__idl_typename__ == "unique_identifier_msgs::msg::dds_::UUID_"


def test_performer_status_state_is_int8_as_upstream() -> None:
    """The drift that kept PlanSys2 performers out: upstream declares ``int8 state``."""
    cls = dds_type("plansys2_msgs/msg/ActionPerformerStatus")
    assert cls.__annotations__["state"] == t.int8
    store = ros2_typestore()
    assert dict(store.fielddefs["plansys2_msgs/msg/ActionPerformerStatus"][1])["state"] == (
        1,
        ("int8", 0),
    )


def test_dds_bytes_equal_rosbags_cdr_for_nested_messages() -> None:
    store = ros2_typestore()
    sample = dds_type("nav_msgs/msg/Odometry")()
    sample.header.frame_id = "odom"
    sample.pose.pose.position.x = 1.5
    sample.twist.covariance[35] = 0.25
    ros = store.deserialize_cdr(bytes(sample.serialize()), "nav_msgs/msg/Odometry")
    assert ros.header.frame_id == "odom" and ros.pose.pose.position.x == 1.5
    assert bytes(store.serialize_cdr(ros, "nav_msgs/msg/Odometry")) == bytes(sample.serialize())


def test_mcap_schema_is_the_msg_text_with_its_dependencies() -> None:
    text, encoding = mcap_schema("plansys2_msgs/msg/Plan")
    assert encoding == "ros2msg"
    assert text.startswith("plansys2_msgs/PlanItem[] items\n")
    assert "MSG: plansys2_msgs/PlanItem\nfloat32 time\nstring action\nfloat32 duration" in text


def test_unknown_type_names_are_one_clear_error() -> None:
    from plansys_bridge.interfaces.definitions import InterfaceError

    with pytest.raises(InterfaceError, match="unknown ROS 2 message type 'std_msgs/msg/Nope'"):
        dds_type("std_msgs/msg/Nope")
    with pytest.raises(InterfaceError, match="not a ROS 2 type name"):
        dds_type("String")
