"""Recorded CAN traffic (candump, ASC, BLF) played back onto a virtual bus, in mission time.

``replay: {log: runs/base1.asc}`` on a ``can`` performer takes the place of the
base: the frames the base sent (``Rx`` in the log) go out on the performer's
``virtual`` channel at their recorded offsets (divided by ``rate``) on the mission
clock, so the performer decodes them with its own DBC, follows the recorded
odometry, heartbeat and faults, and sensing rules fire from the recorded values, on
the virtual clock in no time. Frames the planner sent (``Tx``) are left out unless
``include_tx: true``. When the log ends the base falls silent, as a base that lost
power would.

The log is read with python-can's readers (``can.LogReader`` picks
CanutilsLogReader for ``.log``, ASCReader for ``.asc``, BLFReader for ``.blf``) and
checked whole before anything starts: a line the reader cannot parse (also one
ASCReader would skip without a word: anything that is not a header, comment,
trigger-block line or timestamped event), a file that is not text, an ASC file
without its closing ``End TriggerBlock`` or a BLF file shorter than its header says
is one :class:`ReplayLogError` naming the file and the byte offset (and the line,
for text logs).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import re
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import can
from can.io.blf import BLFParseError

from plansys_bridge.cancellation import cancel_and_wait
from plansys_bridge.clock import Clock
from plansys_bridge.errors import AdapterError

__all__ = ["LogReplay", "LogSummary", "ReplayLogError", "ReplaySettings", "read_log"]

_LOG = logging.getLogger(__name__)

SUFFIXES = (".log", ".asc", ".blf")


class ReplayLogError(AdapterError):
    """A CAN log that cannot be replayed; the message names the file and the offset."""


@dataclass(frozen=True)
class ReplaySettings:
    log: Path
    rate: float = 1.0
    """2.0 plays twice as fast as recorded."""
    include_tx: bool = False
    """Also replay the frames the recording side sent (commands)."""


@dataclass(frozen=True)
class LogSummary:
    frames: int
    first: float
    last: float

    @property
    def duration(self) -> float:
        return self.last - self.first


_ASC_HEADER = re.compile(
    r"(//|date\s|base\s|(no\s+)?internal\s+events\s+logged|begin\s+triggerblock|"
    r"end\s+triggerblock)",
    re.IGNORECASE,
)
_ASC_TIME = re.compile(r"\d+\.\d+")
_ASC_EVENT_WORD = re.compile(r"[A-Za-z][A-Za-z0-9_]*:?")
_HEX_ID = re.compile(r"[0-9A-Fa-f]+[xX]?")
_CANDUMP = re.compile(
    r"\(\d+(\.\d+)?\)\s+\S+\s+[0-9A-Fa-f]{1,8}#"
    r"([Rr]\d*|#[0-9A-Fa-f]([0-9A-Fa-f]{2})*|([0-9A-Fa-f]{2})*)(\s+[RrTt])?"
)


def _asc_event(word: str) -> bool:
    return bool(_ASC_EVENT_WORD.fullmatch(word)) and not _HEX_ID.fullmatch(word)


def _asc_check(text: str, produced: bool) -> str | None:
    """Why a line ASCReader skipped is garbled, or None when it is one the format allows
    and the reader ignores on purpose: header and trigger-block lines, comments, and
    timestamped events (``Start of measurement``, ``Statistic:``, chip status, J1939,
    system variables). A line that yielded a frame is the reader's to judge."""
    line = text.strip()
    if produced or not line or _ASC_HEADER.match(line):
        return None
    tokens = line.split()
    if not _ASC_TIME.fullmatch(tokens[0]):
        return "neither a header, a comment nor a timestamped frame or event"
    if len(tokens) < 3:
        return "a timestamp without a frame or event after it"
    channel, word = tokens[1], tokens[2]
    if (channel.isdigit() and _asc_event(word)) or (not channel.isdigit() and _asc_event(channel)):
        return None
    return "a frame python-can's ASC reader cannot parse (it would skip it)"


def _candump_check(text: str, produced: bool) -> str | None:
    """Why a candump line is garbled: CanutilsLogReader raises on most bad lines but
    reads an odd number of data digits or a stray suffix without complaint."""
    line = text.strip()
    if not produced or _CANDUMP.fullmatch(line):
        return None
    return "not a candump frame (TIME) IFACE ID#DATA with whole data bytes"


class _Lines:
    """A text log handed to a python-can reader line by line, remembering where each
    line started, so that a line the reader chokes on can be named. ``check`` sees
    every line once the reader has moved past it, with whether it gave a frame, so a
    line the reader skips quietly is reported too."""

    def __init__(self, path: Path, check: Callable[[str, bool], str | None]) -> None:
        self.path = path
        self.line = 0
        self.offset = 0
        self._next = 0
        self.last_text = ""
        self.produced = False
        self._check = check
        # ASCReader loops over the file twice (header, then body): one pass, shared
        self._lines = self._read()

    def __iter__(self) -> Iterator[str]:
        return self._lines

    def _read(self) -> Iterator[str]:
        with self.path.open("rb") as raw:
            for data in raw:
                self._checked()
                self.line += 1
                self.offset, self._next = self._next, self._next + len(data)
                try:
                    text = data.decode("utf-8")
                except UnicodeDecodeError as exc:
                    raise ReplayLogError(
                        f"{self.where()}: not a text log line (byte {exc.start + 1} of the line "
                        "is not UTF-8)"
                    ) from exc
                self.last_text = text
                self.produced = False
                yield text
            self._checked()

    def _checked(self) -> None:
        if self.line and (reason := self._check(self.last_text, self.produced)):
            raise ReplayLogError(f"{self.where()}: {reason}: {self.last_text.strip()[:60]!r}")

    def where(self) -> str:
        return f"{self.path}:{self.line} (byte offset {self.offset})"

    # python-can's readers close what they were given
    def close(self) -> None:
        return None


def _reader(path: Path) -> tuple[Any, _Lines | None]:
    suffix = path.suffix.lower()
    if suffix == ".log":
        lines = _Lines(path, _candump_check)
        return can.CanutilsLogReader(lines), lines  # type: ignore[arg-type]
    if suffix == ".asc":
        lines = _Lines(path, _asc_check)
        return can.ASCReader(lines), lines  # type: ignore[arg-type]
    if suffix == ".blf":
        try:
            return can.BLFReader(str(path)), None
        except (BLFParseError, struct.error) as exc:
            raise ReplayLogError(f"{path} (byte offset 0): not a BLF file: {exc}") from exc
    raise ReplayLogError(
        f"{path}: unknown log format {suffix or '(no suffix)'!r}: "
        "candump .log, Vector .asc or Vector .blf"
    )


def read_log(path: Path, include_tx: bool = False) -> Iterator[can.Message]:
    """The log's frames in order; ReplayLogError (file and offset) on a bad one."""
    if not path.is_file():
        raise ReplayLogError(f"{path}: no such CAN log")
    reader, lines = _reader(path)
    try:
        for msg in reader:
            if lines is not None:
                lines.produced = True
            if msg.is_error_frame or include_tx or msg.is_rx:
                yield msg
    except ReplayLogError:
        raise
    except BLFParseError as exc:
        raise ReplayLogError(
            f"{path} (byte offset {_tell(reader)}): bad BLF object: {exc}"
        ) from exc
    except (ValueError, IndexError, KeyError, struct.error, can.CanError) as exc:
        if lines is not None:
            text = lines.last_text.strip()[:60]
            raise ReplayLogError(
                f"{lines.where()}: not a frame of this log format ({exc}): {text!r}"
            ) from exc
        offset = _tell(reader)
        raise ReplayLogError(f"{path} (byte offset {offset}): bad BLF object: {exc}") from exc
    finally:
        with contextlib.suppress(Exception):
            reader.stop()
    _check_complete(path, reader, lines)


def _tell(reader: Any) -> int | str:
    try:
        return int(reader.file.tell())
    except Exception:
        return "?"


def _check_complete(path: Path, reader: Any, lines: _Lines | None) -> None:
    """The readers stop quietly at a cut-off end; say so instead."""
    size = path.stat().st_size
    if path.suffix.lower() == ".asc":
        assert lines is not None
        if "end triggerblock" not in lines.last_text.lower():
            raise ReplayLogError(
                f"{path}:{lines.line} (byte offset {lines.offset}): the log is truncated "
                "(no 'End TriggerBlock' at its end)"
            )
    elif path.suffix.lower() == ".log":
        assert lines is not None
        if lines.last_text and not lines.last_text.endswith("\n"):
            raise ReplayLogError(
                f"{lines.where()}: the log is truncated (its last line is cut off)"
            )
    else:
        expected = int(getattr(reader, "file_size", 0) or 0)
        if expected and size < expected:
            raise ReplayLogError(
                f"{path} (byte offset {size}): the log is truncated "
                f"(its header says {expected} bytes)"
            )


def summarize(path: Path, include_tx: bool = False) -> LogSummary:
    """Read the whole log once (every frame checked); how many frames, and when."""
    frames = 0
    first = last = 0.0
    for msg in read_log(path, include_tx):
        if frames == 0:
            first = msg.timestamp
        last = msg.timestamp
        frames += 1
    if frames == 0:
        raise ReplayLogError(f"{path}: no frames to replay")
    return LogSummary(frames, first, last)


class LogReplay:
    """Sends a checked log's frames on a virtual channel at their recorded times."""

    def __init__(self, clock: Clock, channel: str, settings: ReplaySettings) -> None:
        self.clock = clock
        self.channel = channel
        self.settings = settings
        self.summary = summarize(settings.log, settings.include_tx)
        self.sent = 0
        self.finished = asyncio.Event()
        self._bus: can.BusABC | None = None
        self._task: asyncio.Task[None] | None = None

    async def start(self) -> None:
        self._bus = can.Bus(interface="virtual", channel=self.channel)
        self._task = asyncio.get_running_loop().create_task(
            self._play(), name=f"can-replay {self.settings.log.name}"
        )

    async def _play(self) -> None:
        assert self._bus is not None
        start = self.clock.now()
        first = self.summary.first
        rate = self.settings.rate
        try:
            for msg in read_log(self.settings.log, self.settings.include_tx):
                due = start + (msg.timestamp - first) / rate
                wait = due - self.clock.now()
                if wait > 0:
                    await self.clock.sleep(wait)
                self._bus.send(msg)
                self.sent += 1
        except ReplayLogError as exc:  # the file changed since it was checked
            _LOG.error("%s", exc)
        finally:
            self.finished.set()
        _LOG.info("%s: replayed %d frames; the base is silent now", self.settings.log, self.sent)

    async def stop(self) -> None:
        if self._task is not None:
            await cancel_and_wait(self._task)
            self._task = None
        if self._bus is not None:
            self._bus.shutdown()
            self._bus = None


def parse_replay(value: object, base_dir: Path, key: str) -> ReplaySettings | None:
    """A performer's ``replay:`` (``{log, rate, include_tx}`` or just the log's path),
    with the log read and checked now; errors name the key (and file and offset)."""
    from plansys_bridge.errors import ConfigError

    if value is None or value is False:
        return None
    if isinstance(value, str):
        value = {"log": value}
    if not isinstance(value, dict):
        raise ConfigError("expected {log: FILE, rate: 1.0, include_tx: false}", key=key)
    unknown = sorted(set(value) - {"log", "rate", "include_tx"})
    if unknown:
        raise ConfigError("unknown key (allowed: include_tx, log, rate)", key=f"{key}.{unknown[0]}")
    log = value.get("log")
    if not isinstance(log, str) or not log:
        raise ConfigError("the recorded log: a candump .log, .asc or .blf file", key=f"{key}.log")
    rate = value.get("rate", 1.0)
    if isinstance(rate, bool) or not isinstance(rate, int | float) or not rate > 0:
        raise ConfigError(f"must be a number > 0, got {rate!r}", key=f"{key}.rate")
    include_tx = value.get("include_tx", False)
    if not isinstance(include_tx, bool):
        raise ConfigError(f"must be true or false, got {include_tx!r}", key=f"{key}.include_tx")
    path = Path(log).expanduser()
    settings = ReplaySettings(
        path if path.is_absolute() else base_dir / path, float(rate), include_tx
    )
    try:
        summarize(settings.log, include_tx)
    except ReplayLogError as exc:
        raise ConfigError(str(exc), key=f"{key}.log") from exc
    return settings
