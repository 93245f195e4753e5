"""TCPROS framing: connection headers and length-prefixed messages.

Every TCPROS connection starts with one header from each side: a 4-byte
little-endian length, then fields, each a 4-byte length and ``key=value`` bytes.
After the headers each message is a 4-byte length and the ROS 1 serialised body.
Anything that does not parse is a :class:`ProtocolError`; the caller drops that one
connection and says which topic and peer it was.
"""

from __future__ import annotations

import asyncio
import struct

from plansys_bridge.ros1.errors import ProtocolError

__all__ = [
    "MAX_FRAME",
    "MAX_HEADER",
    "decode_header",
    "encode_header",
    "frame",
    "read_frame",
    "read_header",
]

MAX_HEADER = 1 << 20
"""Largest connection header accepted (message definitions are a few kB)."""

MAX_FRAME = 1 << 30
"""Largest message accepted (1 GiB, images and point clouds included)."""

_LEN = struct.Struct("<I")


def encode_header(fields: dict[str, str]) -> bytes:
    """The header with its leading total length."""
    body = b"".join(
        _LEN.pack(len(item)) + item
        for item in (f"{key}={value}".encode() for key, value in fields.items())
    )
    return _LEN.pack(len(body)) + body


def decode_header(body: bytes) -> dict[str, str]:
    """Fields of a header body (without its leading total length)."""
    fields: dict[str, str] = {}
    pos = 0
    while pos < len(body):
        if pos + 4 > len(body):
            raise ProtocolError(f"header field length cut short at byte {pos}")
        (size,) = _LEN.unpack_from(body, pos)
        pos += 4
        if pos + size > len(body):
            raise ProtocolError(f"header field of {size} bytes overruns the header at byte {pos}")
        item = body[pos : pos + size]
        pos += size
        key, sep, value = item.partition(b"=")
        if not sep or not key:
            raise ProtocolError(f"header field {item[:40]!r} is not key=value")
        try:
            fields[key.decode()] = value.decode()
        except UnicodeDecodeError as exc:
            raise ProtocolError(f"header field {item[:40]!r} is not UTF-8") from exc
    return fields


def frame(body: bytes) -> bytes:
    return _LEN.pack(len(body)) + body


async def _read_sized(reader: asyncio.StreamReader, limit: int, what: str) -> bytes:
    try:
        (size,) = _LEN.unpack(await reader.readexactly(4))
    except asyncio.IncompleteReadError as exc:
        if exc.partial:
            raise ProtocolError(f"{what} length cut short") from exc
        raise EOFError from exc
    if size > limit:
        raise ProtocolError(f"{what} of {size} bytes exceeds the limit of {limit}")
    try:
        return await reader.readexactly(size)
    except asyncio.IncompleteReadError as exc:
        raise ProtocolError(f"{what} cut short: {len(exc.partial)} of {size} bytes") from exc


async def read_header(reader: asyncio.StreamReader) -> dict[str, str]:
    """One connection header; EOFError if the peer closed before sending anything."""
    return decode_header(await _read_sized(reader, MAX_HEADER, "connection header"))


async def read_frame(reader: asyncio.StreamReader) -> bytes:
    """One message body; EOFError on a clean close between messages."""
    return await _read_sized(reader, MAX_FRAME, "message")
