"""Read a mission recording record by record, knowing where each message sits in its file.

rosbags opens an MCAP file through the summary at its end, so a recording whose
process was killed (no summary, no footer) cannot be opened at all, and damage
inside a chunk may go unnoticed (its messages are silently missing). Reading the
file front to back with mcap's stream reader, with chunk CRCs checked, instead
tells where a recording breaks: every error names the file and the byte offset of
the record that could not be read, and every message carries the offset of the
record (chunk) it came from, so a message that does not decode is named the same
way.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, cast

from plansys_bridge.errors import PlansysBridgeError

__all__ = ["McapScanError", "RecordedMessage", "mcap_files", "scan_mcap"]


class McapScanError(PlansysBridgeError):
    """A recording that is damaged or truncated at a known place."""

    def __init__(self, file: Path, offset: int, reason: str) -> None:
        self.file = file
        self.offset = offset
        self.reason = reason
        super().__init__(f"{file}: offset {offset}: {reason}")


@dataclass(frozen=True)
class RecordedMessage:
    topic: str
    msgtype: str
    log_time: int
    """Nanoseconds (mission time for the project's recordings)."""
    data: bytes
    """The serialised message (CDR for ROS 2 bags)."""
    file: Path
    offset: int
    """Byte offset of the record holding the message (a chunk, or the message itself)."""
    index: int = 0
    """Position of the message inside its chunk (0 for a message outside chunks)."""

    @property
    def place(self) -> str:
        inside = f" (message {self.index + 1} of the chunk)" if self.index else ""
        return f"{self.file}: offset {self.offset}{inside}"


class _Counting:
    """A file wrapper that knows how many bytes were read (the stream reader keeps
    no public position)."""

    def __init__(self, raw: IO[bytes]) -> None:
        self.raw = raw
        self.pos = 0

    def read(self, size: int = -1) -> bytes:
        data = self.raw.read(size)
        self.pos += len(data)
        return data


def mcap_files(path: Path) -> list[Path]:
    """The MCAP files of a recording: the file itself, or a bag folder's files in
    the order its ``metadata.yaml`` lists them (else sorted by name)."""
    if path.is_file():
        return [path]
    if not path.is_dir():
        return []
    listed = _listed_files(path)
    return listed if listed else sorted(path.glob("*.mcap"))


def _listed_files(folder: Path) -> list[Path]:
    import yaml

    meta = folder / "metadata.yaml"
    try:
        info = yaml.safe_load(meta.read_text(encoding="utf-8"))
        names = info["rosbag2_bagfile_information"]["relative_file_paths"]
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        return []
    if not isinstance(names, list):
        return []
    return [folder / str(n) for n in names if str(n).endswith(".mcap")]


def scan_mcap(file: Path, topics: set[str] | None = None) -> Iterator[RecordedMessage]:
    """Every message of ``file`` (only ``topics`` when given), in file order.

    Raises :class:`McapScanError` naming the offset where the file cannot be read
    on: a missing or wrong magic, a record running past the end of the file, a chunk
    whose CRC does not match or that cannot be decompressed, a message of a channel
    never declared, or a file that ends before its footer.
    """
    from mcap import records as rec
    from mcap.exceptions import EndOfFile, InvalidMagic, McapError
    from mcap.stream_reader import StreamReader, breakup_chunk

    try:
        size = file.stat().st_size
        raw = file.open("rb")
    except OSError as exc:
        raise McapScanError(file, 0, f"cannot open: {exc.strerror or exc}") from exc
    with raw:
        stream = _Counting(raw)
        reader = StreamReader(cast(IO[bytes], stream), emit_chunks=True, validate_crcs=True)
        records = iter(reader.records)
        schemas: dict[int, str] = {}
        channels: dict[int, tuple[str, int]] = {}
        start = 0
        while True:
            start = stream.pos
            try:
                record: Any = next(records)
            except StopIteration:
                return
            except EndOfFile as exc:
                raise McapScanError(file, start, _truncated(start, size)) from exc
            except InvalidMagic as exc:
                what = "not an MCAP file (no MCAP magic)" if start == 0 else "damaged end magic"
                raise McapScanError(file, start, what) from exc
            except (McapError, ValueError, struct.error, MemoryError) as exc:
                what = "not an MCAP file" if start == 0 else "damaged record"
                raise McapScanError(file, start, f"{what}: {_describe(exc)}") from exc
            if isinstance(record, rec.Chunk):
                try:
                    inner = breakup_chunk(record, validate_crc=True)
                except (McapError, ValueError, struct.error, MemoryError) as exc:
                    raise McapScanError(file, start, f"damaged chunk: {_describe(exc)}") from exc
            else:
                inner = [record]
            for index, item in enumerate(inner):
                if isinstance(item, rec.Schema):
                    schemas[item.id] = item.name
                elif isinstance(item, rec.Channel):
                    channels[item.id] = (item.topic, item.schema_id)
                elif isinstance(item, rec.Message):
                    found = channels.get(item.channel_id)
                    if found is None:
                        raise McapScanError(
                            file, start, f"a message of channel {item.channel_id}, never declared"
                        )
                    topic, schema_id = found
                    if topics is not None and topic not in topics:
                        continue
                    yield RecordedMessage(
                        topic,
                        schemas.get(schema_id, ""),
                        item.log_time,
                        item.data,
                        file,
                        start,
                        index if isinstance(record, rec.Chunk) else 0,
                    )


def _truncated(start: int, size: int) -> str:
    if start >= size:
        return (
            f"truncated: the file ends at byte {size} before its footer "
            "(the recording was not finished)"
        )
    return (
        f"truncated: the record starting here runs past the end of the file at byte {size} "
        "(the recording was not finished)"
    )


def _describe(exc: BaseException) -> str:
    text = str(exc)
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
