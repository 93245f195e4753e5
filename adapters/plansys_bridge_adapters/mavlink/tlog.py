"""Reading MAVLink telemetry logs (``.tlog``, as MAVProxy and Mission Planner write them).

A tlog is every packet of a link, each after an 8-byte big-endian microsecond
timestamp. pymavlink reads it (``mavutil.mavlink_connection(path)``) and stamps each
message with ``_timestamp``; here the file gets its own MAVLink 2 codec (the live
link's reason: pymavlink's global dialect switch would change other links of the
process) and is checked whole before a replay starts: a packet that does not parse
(``BAD_DATA``: bad CRC, bad prefix), a timestamp that runs backwards or a packet cut
off at the end is one :class:`TlogError` naming the file and the byte offset.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from plansys_bridge.errors import AdapterError

__all__ = ["TlogError", "TlogSummary", "read_tlog", "summarize_tlog"]


class TlogError(AdapterError):
    """A telemetry log that cannot be replayed; names the file and the byte offset."""


@dataclass(frozen=True)
class TlogSummary:
    messages: int
    first: float
    last: float
    systems: frozenset[int]


def _open(path: Path) -> Any:
    if not path.is_file():
        raise TlogError(f"{path}: no such telemetry log")
    try:
        conn = mavutil.mavlink_connection(str(path), notimestamps=False)
    except (OSError, ValueError) as exc:
        raise TlogError(f"{path}: cannot read: {exc}") from exc
    conn.mav = mavlink2.MAVLink(conn)
    conn.mav.robust_parsing = True
    return conn


def read_tlog(path: Path) -> Iterator[Any]:
    """Every message of the log in order (``msg._timestamp`` in seconds)."""
    conn = _open(path)
    last_stamp = None
    try:
        while True:
            msg = conn.recv_msg()
            if msg is None:
                break
            offset = conn.f.tell()
            if msg.get_type() == "BAD_DATA":
                reason = str(getattr(msg, "reason", "") or "not a MAVLink packet")
                raise TlogError(f"{path} (byte offset {offset}): {reason}")
            stamp = float(msg._timestamp)
            if last_stamp is not None and stamp < last_stamp:
                raise TlogError(
                    f"{path} (byte offset {offset}): timestamp {stamp:.6f} runs back from "
                    f"{last_stamp:.6f} (not a telemetry log, or damaged)"
                )
            last_stamp = stamp
            yield msg
        left = conn.mav.buf_len()
        if left:
            size = path.stat().st_size
            raise TlogError(
                f"{path} (byte offset {size - left}): the log is truncated "
                f"(the last {left} bytes are part of a packet)"
            )
    finally:
        with contextlib.suppress(Exception):
            conn.close()


def summarize_tlog(path: Path) -> TlogSummary:
    """Read the whole log once, checking every packet."""
    count = 0
    first = last = 0.0
    systems: set[int] = set()
    for msg in read_tlog(path):
        if count == 0:
            first = msg._timestamp
        last = msg._timestamp
        systems.add(msg.get_srcSystem())
        count += 1
    if count == 0:
        raise TlogError(f"{path}: no MAVLink messages in it")
    return TlogSummary(count, first, last, frozenset(systems))
