"""A CAN log's garbled line, anywhere in it, is one error naming file, line and byte
offset, while the lines python-can's readers skip on purpose (comments, headers,
events) are still accepted. The logs are written by python-can's own writers and then
edited by hand, the way a damaged copy or a hand-merged log looks."""

from __future__ import annotations

from pathlib import Path

import can
import pytest
from plansys_bridge_adapters.can.replay import ReplayLogError, read_log, summarize

FRAMES = [
    can.Message(timestamp=10.0 + i * 0.05, arbitration_id=0x200 + i % 3, data=bytes([i] * 4))
    for i in range(40)
]


def _asc(tmp_path: Path) -> Path:
    """An ASC log python-can wrote: frames, a remote frame, an error frame, an FD frame."""
    path = tmp_path / "base.asc"
    writer = can.ASCWriter(str(path))
    for msg in FRAMES:
        writer.on_message_received(msg)
    writer.on_message_received(
        can.Message(timestamp=12.1, arbitration_id=0x7FF, is_remote_frame=True, dlc=2)
    )
    writer.on_message_received(can.Message(timestamp=12.2, is_error_frame=True))
    writer.on_message_received(
        can.Message(timestamp=12.3, arbitration_id=0x123, is_fd=True, data=bytes(range(12)))
    )
    writer.stop()
    return path


def _insert(path: Path, index: int, line: str) -> tuple[Path, int, int]:
    """``line`` put in as the log's line ``index + 1``; (path, line number, offset)."""
    lines = path.read_text().splitlines(keepends=True)
    lines.insert(index, line + "\n")
    path.write_text("".join(lines))
    return path, index + 1, sum(len(x.encode()) for x in lines[:index])


IGNORED_ON_PURPOSE = [
    "// a comment the engineer added",
    "   10.510000 Start of measurement",
    "   10.520000 Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%",
    "   10.530000 1 Statistic: D 10 R 0 XD 0 XR 0 E 0 O 0 B 1.20%",
    "   10.540000 CAN 1 Status:chip status error active",
    "   10.550000 J1939TP FEEBp 6 0 4 - Rx d 23 A0 0F A6 60 3B D1 B3",
    "   10.560000 SV: 3 0 1 ::Battery::Level = 80",
    "   10.570000 1 Overload Frame",
    "",
]


def test_what_the_asc_reader_skips_on_purpose_is_accepted(tmp_path: Path) -> None:
    path = _asc(tmp_path)
    for line in IGNORED_ON_PURPOSE:
        _insert(path, 12, line)
    text = path.read_text()
    assert "base hex  timestamps absolute" in text and "Begin Triggerblock" in text
    msgs = list(read_log(path, include_tx=True))
    assert len(msgs) == len(FRAMES) + 3
    assert [m.data for m in msgs[: len(FRAMES)]] == [m.data for m in FRAMES]
    assert msgs[-2].is_error_frame and msgs[-1].is_fd
    assert summarize(path, include_tx=True).frames == len(FRAMES) + 3


@pytest.mark.parametrize(
    "garbled",
    [
        "this line is not part of any ASC log",
        "   10.6.1 1  201  Rx   d 4 01 02 03 04",  # a broken timestamp
        "   10.610000 1  201  Rq   d 4 01 02 03 04",  # neither Rx nor Tx
        "   10.620000 1  2#1  Rx   d 4 01 02 03 04",  # a broken identifier
        "   10.630000",  # cut after the timestamp
        "   10.640000 1 ",
        "Begn Triggerblock Thu Jan 01 00:00:00.10 1970",
    ],
)
@pytest.mark.parametrize("where", [6, 30])
def test_a_garbled_asc_line_is_named_by_line_and_offset(
    tmp_path: Path, garbled: str, where: int
) -> None:
    path, line, offset = _insert(_asc(tmp_path), where, garbled)
    with pytest.raises(ReplayLogError) as info:
        summarize(path, include_tx=True)
    assert f"{path}:{line} (byte offset {offset}): " in str(info.value)
    assert repr(garbled.strip()[:60]) in str(info.value)


def test_a_garbled_candump_line_is_named_by_line_and_offset(tmp_path: Path) -> None:
    path = tmp_path / "base.log"
    writer = can.CanutilsLogWriter(str(path))
    for msg in FRAMES:
        writer.on_message_received(msg)
    writer.stop()
    assert len(list(read_log(path))) == len(FRAMES)
    # python-can's reader turns the odd digit into a byte of its own, without a word
    path, line, offset = _insert(path, 20, "(10.990000) can0 201#0102030 R")
    with pytest.raises(ReplayLogError) as info:
        summarize(path)
    assert f"{path}:{line} (byte offset {offset}): not a candump frame" in str(info.value)
