"""``ActionExecution`` straight to and from XCDR1 bytes: the auction's hot path.

Nearly every sample on the hub's DDS topics is an ``ActionExecution``: an auction
among N bidders is a REQUEST, N RESPONSEs, a CONFIRM and N-1 REJECTs, all naming the
same action and arguments (and, wrapped, the same request id). The generated codec
of :mod:`~plansys_bridge.hub.dds_wire` writes and reads every field of every sample;
here what varies inside one auction (``type``, node name, bid) is written and read
per sample, and the rest is written once per distinct value and read once per
distinct bytes. A wrapped message (``plansys_bridge_msgs/ActionExecution``) is
written from and read into the hub's :class:`~plansys_bridge.hub.messages.ActionExecution`
without the wrapper object.

Why the parts can be kept:

* the front (encapsulation header, ``type``, node name) ends 4-aligned, and the
  body after it (action, arguments, success, completion, status, padded to 4) holds
  no 8-byte field, so the bytes of each depend on its own fields only;
* reading, the bytes after the node name up to the bid (the whole rest of a plain
  sample) give the same fields whenever they are the same bytes at an offset of the
  same remainder modulo 8 (the padding before the bid depends on it), and the sample
  then ends with the bid: a kept entry is used only for such a sample, and only
  samples read to their last byte are kept.
* reading, the bytes up to the end of the node name's padding (encapsulation header,
  ``type``, node name) give the same type and node name whenever they are the same
  bytes: the length they hold is where they end;
* writing, a wrapped sample's body and request id, and the flag and padding of its
  bid, depend on the front's length modulo 8 besides their own fields (kept as one
  part: every message of one auction shares it).

The bytes are exactly those of the generated codec (a property test compares them,
and the generated codec is compared with Cyclone's own serialiser).
"""

from __future__ import annotations

import math
import struct
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
_CACHE = 4096
"""Writing: parts kept per cache (one per node name, a few per action and request)."""
_KEPT = 1024
"""Reading: rests kept per reader (a few per auction)."""

# -- writing --------------------------------------------------------------------------------


@lru_cache(maxsize=_CACHE)
def _front(kind: int, node_id: str) -> bytes:
    """Encapsulation header, ``type``, its padding and the node name, padded to 4."""
    node = string_bytes(node_id)
    return _HEADER + _I16.pack(kind) + b"\x00\x00" + node + _ZEROS[-len(node) & 3]


@lru_cache(maxsize=_CACHE)
def _body(
    action: str, arguments: tuple[str, ...], success: bool, completion: bytes, status: str
) -> bytes:
    """Action, arguments, success, completion (packed: 0.0 and -0.0 are equal keys but
    not equal bytes) and status from a 4-aligned offset, padded to 4."""
    out = bytearray(string_bytes(action))
    out += _ZEROS[-len(out) & 3]
    out += strings_bytes(arguments)
    out += _BOOL.pack(success)
    out += _ZEROS[-len(out) & 3]
    out += completion
    out += string_bytes(status)
    out += _ZEROS[-len(out) & 3]
    return bytes(out)


# After the request id: ``has_bid``, the padding to 8 (counted from after the 4-byte
# encapsulation header) and, without a bid, the 0.0 in its place; by the length so
# far modulo 8 (header included).
_BID_FLAG = tuple(b"\x01" + _ZEROS[-(n - 3) & 7] for n in range(8))
_NO_BID = tuple(b"\x00" + _ZEROS[-(n - 3) & 7] + _F64.pack(0.0) for n in range(8))


@lru_cache(maxsize=_CACHE)
def _tail(
    front: int,
    action: str,
    arguments: tuple[str, ...],
    success: bool,
    completion: bytes,
    status: str,
    request_id: str,
) -> tuple[bytes, bytes]:
    """What follows a wrapped sample's front of length ``front`` modulo 8 (0 or 4):
    the body, the request id and, without a bid, the rest of the sample; with one, all
    but the bid itself. The part all messages of one auction share, kept whole."""
    head = _body(action, arguments, success, completion, status) + string_bytes(request_id)
    at = (front + len(head)) & 7
    return head + _NO_BID[at], head + _BID_FLAG[at]


def execution_writer(ros_type: str) -> Callable[[hm.ActionExecution], bytes]:
    """hub ActionExecution -> the bytes of a ``ros_type`` sample (PLAIN or WRAPPED);
    ``ValueError`` for a value the type cannot carry."""
    wrapped = ros_type == WRAPPED
    pack_f32 = _F32.pack
    pack_f64 = _F64.pack

    def encode(msg: hm.ActionExecution) -> bytes:
        try:
            front = _front(msg.type, msg.node_id)
            if not wrapped:
                return front + _body(
                    msg.action, msg.arguments, msg.success, pack_f32(msg.completion), msg.status
                )
            no_bid, with_bid = _tail(
                len(front) & 7,
                msg.action,
                msg.arguments,
                msg.success,
                pack_f32(msg.completion),
                msg.status,
                msg.request_id,
            )
            bid = msg.bid
            return front + no_bid if bid is None else front + with_bid + pack_f64(bid)
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


def _read_body(data: bytes, p: int, size: int) -> tuple[dict[str, Any], int]:
    """The fields action .. status at 4-aligned ``p``, and the offset after them."""
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
    fields = {
        "type": None,
        "node_id": None,
        "action": action,
        "arguments": tuple(arguments),
        "success": success,
        "completion": completion,
        "status": status,
        "bid": None,
        "request_id": "",
    }
    return fields, p


def _read_rest(data: bytes, p: int, size: int, wrapped: bool) -> tuple[dict[str, Any], int]:
    """The fields after the node name (all but ``type``, ``node_id`` and ``bid``, in
    their order) and where the bid is (the end, for a plain sample)."""
    fields, p = _read_body(data, p, size)
    if wrapped:
        p += -p & 3
        fields["request_id"], p = _string(data, p, size)
        # has_bid where the bid goes: the reader puts the bid (or None) there
        fields["bid"] = _BOOL.unpack_from(data, p)[0]
        p += 1
        p += -(p - 4) & 7  # 8-aligned counting from after the header
    else:
        p += -p & 3  # Cyclone pads a sample to 4 bytes
    return fields, p


def _read_front(data: bytes, size: int) -> tuple[tuple[hm.ExecutionType, str], int]:
    """The type and node name of an XCDR1 sample, and the 4-aligned offset after them."""
    value = _I16.unpack_from(data, 4)[0]
    kind = _KINDS.get(value)
    if kind is None:
        raise ValueError(f"{PLAIN}.type is {value!r}, not one of {_KNOWN}")
    n = _U32.unpack_from(data, 8)[0]
    p = 12 + n
    if n == 0 or p > size:
        raise ValueError(f"string length {n} past the end")
    node = data[12 : p - 1].decode()
    return (kind, node), p + (-p & 3)


def execution_reader(
    ros_type: str, fallback: Callable[[bytes], hm.ActionExecution]
) -> Callable[[bytes], hm.ActionExecution]:
    """bytes of a ``ros_type`` sample (PLAIN or WRAPPED) -> the hub ActionExecution.

    Checks as the generated reader does (a known ``type``, finite numbers; ``ValueError``
    otherwise); a sample in another representation goes to ``fallback``. The kept
    parts (see the module docs) live in plain dictionaries, looked up and filled in
    single steps: reader threads of several transports may share one reader.
    """
    wrapped = ros_type == WRAPPED
    kept: tuple[dict[bytes, dict[str, Any]], ...] = ({}, {})
    """By the remainder modulo 8 of where the rest starts (0 or 4): its bytes -> fields."""
    fronts: dict[bytes, tuple[hm.ExecutionType, str]] = {}
    """A sample's bytes up to the rest (header, type, node name, padding) -> its type
    and node name: an auction's samples come from the same few nodes, and bytes that
    are a kept front are that front whatever follows them."""
    new = object.__new__
    cls = hm.ActionExecution
    unpack_u32 = _U32.unpack_from
    unpack_f64 = _F64.unpack_from
    isfinite = math.isfinite

    def read(data: bytes) -> hm.ActionExecution:
        size = len(data)
        try:
            # header, type, node name and padding, as kept: (12 + n) rounded up to 4
            p = (15 + unpack_u32(data, 8)[0]) & -4
            front = fronts.get(data[:p])
        except struct.error:  # too short to say: read as below
            front = None
        if front is None and data[:2] != XCDR1_LE:
            return fallback(data)
        try:
            if front is None:
                front, p = _read_front(data, size)
                if len(fronts) >= _KEPT:
                    fronts.clear()
                fronts[data[:p]] = front
            kind, node = front
            end = size - 8 if wrapped else size
            table = kept[(p & 4) >> 2]
            fields = table.get(data[p:end])
            if fields is None:
                fields, at = _read_rest(data, p, size, wrapped)
                if at == end:  # read to its last byte: the bytes tell the fields
                    if len(table) >= _KEPT:
                        table.clear()
                    table[data[p:end]] = fields
            else:
                at = end
            msg = new(cls)
            vars_ = msg.__dict__
            vars_.update(fields)
            vars_["type"] = kind
            vars_["node_id"] = node
            if wrapped:
                bid = unpack_f64(data, at)[0]
                if not isfinite(bid):
                    raise ValueError(f"{WRAPPED}.bid is {bid!r}, not a finite number")
                vars_["bid"] = bid if fields["bid"] else None
        except (struct.error, IndexError, UnicodeDecodeError) as exc:
            raise ValueError(f"{ros_type}: malformed sample: {exc}") from exc
        return msg

    return read
