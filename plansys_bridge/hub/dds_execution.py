"""``ActionExecution`` straight to and from XCDR1 bytes: the auction's hot path.

Nearly every sample on the hub's DDS topics is an ``ActionExecution``: an auction
among N bidders is a REQUEST, N RESPONSEs, a CONFIRM and N-1 REJECTs, all naming the
same action and arguments. The generated codec of :mod:`~plansys_bridge.hub.dds_wire`
writes and reads every field of every sample; here the part of a sample after its
node name (action, arguments, success, completion, status: the "body") is written
once per distinct body and read once per distinct body bytes, and a wrapped message
(``plansys_bridge_msgs/ActionExecution``) is written from and read into the hub's
:class:`~plansys_bridge.hub.messages.ActionExecution` without the wrapper object.

Why the body can be kept: it starts 4-aligned right after the node name and holds
no 8-byte field, so its bytes depend on its own fields only, and reading the same
bytes from a 4-aligned offset always gives the same fields and the same length. The
bytes are exactly those of the generated codec (a test compares them, and the
generated codec is compared with Cyclone's own serialiser).
"""

from __future__ import annotations

import math
import struct
import threading
from collections.abc import Callable
from functools import lru_cache
from typing import Any

from plansys_bridge.hub import messages as hm
from plansys_bridge.hub.dds_wire import XCDR1_LE, string_bytes, strings_bytes

__all__ = ["PLAIN", "WRAPPED", "execution_reader", "execution_writer"]

PLAIN = "plansys2_msgs/msg/ActionExecution"
WRAPPED = "plansys_bridge_msgs/msg/ActionExecution"

_HEADER = b"\x00\x01\x00\x00"
_ZEROS = tuple(bytes(n) for n in range(8))
_I16 = struct.Struct("<h")
_U32 = struct.Struct("<I")
_F32 = struct.Struct("<f")
_F64 = struct.Struct("<d")
_BOOL = struct.Struct("<?")
_KINDS = {kind.value: kind for kind in hm.ExecutionType}
_KNOWN = ", ".join(f"{kind.name}={kind.value}" for kind in hm.ExecutionType)
_BODY_CACHE = 1024


@lru_cache(maxsize=64)
def _head(kind: int) -> bytes:
    """Encapsulation header, ``type`` and the padding before the node name."""
    return _HEADER + _I16.pack(kind) + b"\x00\x00"


@lru_cache(maxsize=_BODY_CACHE)
def _body(
    action: str, arguments: tuple[str, ...], success: bool, completion: bytes, status: str
) -> bytes:
    """Action, arguments, success, completion (packed: 0.0 and -0.0 are equal keys but
    not equal bytes) and status from a 4-aligned offset."""
    out = bytearray(string_bytes(action))
    out += _ZEROS[-len(out) & 3]
    out += strings_bytes(arguments)
    out += _BOOL.pack(success)
    out += _ZEROS[-len(out) & 3]
    out += completion
    out += string_bytes(status)
    return bytes(out)


def _write_plain(msg: hm.ActionExecution) -> bytes:
    node = string_bytes(msg.node_id)
    body = _body(
        msg.action, msg.arguments, bool(msg.success), _F32.pack(msg.completion), msg.status
    )
    offset = 4 + len(node)
    pad = -offset & 3
    offset += pad + len(body)
    return b"".join((_head(msg.type), node, _ZEROS[pad], body, _ZEROS[-offset & 3]))


def _write_wrapped(msg: hm.ActionExecution) -> bytes:
    node = string_bytes(msg.node_id)
    body = _body(
        msg.action, msg.arguments, bool(msg.success), _F32.pack(msg.completion), msg.status
    )
    request = string_bytes(msg.request_id)
    bid = msg.bid
    offset = 4 + len(node)  # offsets count from after the encapsulation header
    pad = -offset & 3
    offset += pad + len(body)
    pad_request = -offset & 3
    offset += pad_request + len(request) + 1
    pad_bid = -offset & 7
    return b"".join(
        (
            _head(msg.type),
            node,
            _ZEROS[pad],
            body,
            _ZEROS[pad_request],
            request,
            b"\x00" if bid is None else b"\x01",
            _ZEROS[pad_bid],
            _F64.pack(0.0 if bid is None else bid),
        )
    )


def execution_writer(ros_type: str) -> Callable[[hm.ActionExecution], bytes]:
    """hub ActionExecution -> the bytes of a ``ros_type`` sample (PLAIN or WRAPPED);
    ``ValueError`` for a value the type cannot carry."""
    write = _write_wrapped if ros_type == WRAPPED else _write_plain

    def encode(msg: hm.ActionExecution) -> bytes:
        try:
            return write(msg)
        except (struct.error, OverflowError, ValueError, AttributeError, TypeError) as exc:
            raise ValueError(f"{ros_type}: {exc}") from exc

    return encode


# -- reading --------------------------------------------------------------------------------


def _string(data: bytes, p: int, size: int) -> tuple[str, int]:
    """The string at 4-aligned ``p``, and the offset after it."""
    n = _U32.unpack_from(data, p)[0]
    end = p + 4 + n
    if n == 0 or end > size:
        raise ValueError(f"string length {n} past the end")
    return data[p + 4 : end - 1].decode(), end


def _read_body(data: bytes, p: int, size: int) -> tuple[tuple[Any, ...], int]:
    """(action, arguments, success, completion, status) at 4-aligned ``p``, and its end."""
    action, p = _string(data, p, size)
    p += -p & 3
    count = _U32.unpack_from(data, p)[0]
    p += 4
    if count > size - p:
        raise ValueError(f"sequence of {count} items past the end")
    arguments = []
    for _ in range(count):
        p += -p & 3
        item, p = _string(data, p, size)
        arguments.append(item)
    success = _BOOL.unpack_from(data, p)[0]
    p += 1
    p += -p & 3
    completion = _F32.unpack_from(data, p)[0]
    if not math.isfinite(completion):
        raise ValueError(f"{PLAIN}.completion is {completion!r}, not a finite number")
    status, p = _string(data, p + 4, size)
    return (action, tuple(arguments), success, completion, status), p


class _Bodies:
    """Bodies read so far, by their bytes (see the module docs for why that is safe).

    Shared by the reader threads of every transport of the process (the channels
    are), so the lengths to try are an immutable tuple replaced under a lock.
    """

    def __init__(self) -> None:
        self._fields: dict[bytes, tuple[Any, ...]] = {}
        self._lengths: tuple[int, ...] = ()
        """Lengths of the bodies kept, most recent first (a few at a time in practice)."""
        self._lock = threading.Lock()

    def read(self, data: bytes, p: int, size: int) -> tuple[tuple[Any, ...], int]:
        fields = self._fields
        for length in self._lengths:
            found = fields.get(data[p : p + length])
            if found is not None:
                return found, p + length
        found, end = _read_body(data, p, size)
        with self._lock:
            if len(fields) >= _BODY_CACHE:
                fields.clear()
            fields[data[p:end]] = found
            others = [n for n in self._lengths if n != end - p]
            self._lengths = (end - p, *others[:7])
        return found, end


def execution_reader(
    ros_type: str, fallback: Callable[[bytes], hm.ActionExecution]
) -> Callable[[bytes], hm.ActionExecution]:
    """bytes of a ``ros_type`` sample (PLAIN or WRAPPED) -> the hub ActionExecution.

    Checks as the generated reader does (a known ``type``, finite numbers; ``ValueError``
    otherwise); a sample in another representation goes to ``fallback``. One reader
    serves one thread (the transport's reader thread).
    """
    wrapped = ros_type == WRAPPED
    bodies = _Bodies()

    def read(data: bytes) -> hm.ActionExecution:
        if data[:2] != XCDR1_LE:
            return fallback(data)
        size = len(data)
        try:
            value = _I16.unpack_from(data, 4)[0]
            kind = _KINDS.get(value)
            if kind is None:
                raise ValueError(f"{PLAIN}.type is {value!r}, not one of {_KNOWN}")
            node, p = _string(data, 8, size)
            p += -p & 3
            (action, arguments, success, completion, status), p = bodies.read(data, p, size)
            request_id, bid = "", None
            if wrapped:
                p += -p & 3
                request_id, p = _string(data, p, size)
                has_bid = _BOOL.unpack_from(data, p)[0]
                p += 1
                p += -(p - 4) & 7  # 8-aligned counting from after the header
                value = _F64.unpack_from(data, p)[0]
                if not math.isfinite(value):
                    raise ValueError(f"{WRAPPED}.bid is {value!r}, not a finite number")
                bid = value if has_bid else None
        except (struct.error, IndexError, UnicodeDecodeError) as exc:
            raise ValueError(f"{ros_type}: malformed sample: {exc}") from exc
        return hm.action_execution(
            kind,
            node,
            action,
            arguments,
            success=success,
            completion=completion,
            status=status,
            bid=bid,
            request_id=request_id,
        )

    return read
