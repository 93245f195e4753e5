"""XCDR1 little-endian bytes of the hub's DDS samples, compiled once per ROS 2 type.

Cyclone's Python binding serialises a sample by walking a generic tree of type
machines, 30-40 us for one ``ActionExecution`` each way: with every bidder of an
auction answering, that walk was most of an auction's cost over DDS. The functions
here are generated from the same parsed ``.msg`` fields the DDS types come from
(:func:`~plansys_bridge.interfaces.typestore.ros2_fielddefs`), as straight-line
Python with precompiled ``struct`` formats, and produce or read exactly the bytes
Cyclone would (ROS 2's XCDR1: a 4-byte encapsulation header ``00 01 00 00``, fields
in ``.msg`` order, each primitive aligned to its size counted from after the header,
strings and sequences as a uint32 length then the items); a test compares them with
Cyclone's own on every hub type. Samples in any other representation (big-endian,
XCDR2) are left to Cyclone's deserialiser.

Samples are the generated :func:`~plansys_bridge.interfaces.dds.dds_type` classes, so
a sample decoded here is the same object Cyclone would have returned.
"""

from __future__ import annotations

import dataclasses
import enum
import math
import struct
import threading
import typing
from collections.abc import Callable
from functools import lru_cache
from typing import Any

from plansys_bridge.hub.dds_convert import split_seconds
from plansys_bridge.interfaces.convert import DURATION, TIME
from plansys_bridge.interfaces.dds import dds_type
from plansys_bridge.interfaces.typestore import Nodetype, ros2_fielddefs

__all__ = [
    "XCDR1_LE",
    "WireCodec",
    "hub_reader",
    "string_bytes",
    "strings_bytes",
    "wire_codec",
]

XCDR1_LE = b"\x00\x01"
"""The encapsulation identifier of plain CDR, little-endian (what ROS 2 nodes write)."""

_FORMATS: dict[str, str] = {
    "bool": "?",
    "byte": "B",
    "char": "B",
    "int8": "b",
    "uint8": "B",
    "int16": "h",
    "uint16": "H",
    "int32": "i",
    "uint32": "I",
    "int64": "q",
    "uint64": "Q",
    "float32": "f",
    "float64": "d",
}
_ZEROS = tuple(bytes(n) for n in range(8))
_STAMPS = {TIME: "stamp", DURATION: "duration"}
_U32 = struct.Struct("<I")


@lru_cache(maxsize=4096)
def string_bytes(text: str) -> bytes:
    """An unbounded string as XCDR1 writes it (length with the NUL, UTF-8, NUL).

    Kept per text: the hub writes the same node names, actions and arguments over
    and over (an auction among 200 bidders writes one action 400 times), and
    encoding each string was most of an encode.
    """
    data = text.encode()
    return _U32.pack(len(data) + 1) + data + b"\x00"


@lru_cache(maxsize=4096)
def strings_bytes(items: tuple[str | None, ...]) -> bytes:
    """An unbounded sequence of unbounded strings, from a 4-aligned offset (where
    its length goes): the padding inside depends on nothing before it."""
    out = bytearray(_U32.pack(len(items)))
    for item in items:
        out += _ZEROS[-len(out) & 3]
        out += string_bytes("" if item is None else item)
    return bytes(out)


class WireCodec:
    """``encode(sample) -> bytes`` and ``decode(bytes) -> sample`` for one ROS 2 type.

    ``decode`` raises ``ValueError`` for bytes that do not hold a sample of the type
    (cut short, a length past the end, text that is not UTF-8), ``encode`` for a
    value the type cannot carry (out of range, a bound exceeded).
    """

    def __init__(self, ros_type: str) -> None:
        self.ros_type = ros_type
        self._encode, self._decode = _compile(ros_type)

    def encode(self, sample: Any) -> bytes:
        try:
            return self._encode(sample)
        except (struct.error, OverflowError, ValueError, AttributeError, TypeError) as exc:
            raise ValueError(f"{self.ros_type}: {exc}") from exc

    def decode(self, data: bytes) -> Any:
        if data[:2] != XCDR1_LE:
            # Another representation: Cyclone reads every one it can write.
            return dds_type(self.ros_type).deserialize(data)
        try:
            return self._decode(data)
        except (struct.error, IndexError, ValueError) as exc:  # UnicodeDecodeError too
            raise ValueError(f"{self.ros_type}: malformed sample: {exc}") from exc


_lock = threading.Lock()
_codecs: dict[str, WireCodec] = {}


def wire_codec(ros_type: str) -> WireCodec:
    """The codec of ``ros_type`` (compiled on first use, then shared)."""
    with _lock:
        codec = _codecs.get(ros_type)
        if codec is None:
            codec = _codecs[ros_type] = WireCodec(ros_type)
        return codec


def hub_reader(ros_type: str, hub: type, fallback: Callable[[Any], Any]) -> Callable[[bytes], Any]:
    """bytes -> the hub dataclass ``hub``, straight from XCDR1 (no Cyclone sample between).

    Fields are taken by name, enums and finite numbers checked as
    :func:`~plansys_bridge.hub.dds_convert.hub_decoder` does (``ValueError`` naming the
    field); another representation is deserialised by Cyclone and given to
    ``fallback`` (Cyclone sample -> hub message).
    """
    fast = _decoder(ros_type, hub)
    cls = dds_type(ros_type)

    def read(data: bytes) -> Any:
        if data[:2] != XCDR1_LE:
            return fallback(cls.deserialize(data))
        try:
            return fast(data)
        except (struct.error, IndexError, UnicodeDecodeError) as exc:
            raise ValueError(f"{ros_type}: malformed sample: {exc}") from exc

    return read


# -- code generation ----------------------------------------------------------------------


class _Source:
    """Lines of one generated function, with fresh local names and its globals."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.env: dict[str, Any] = {
            "_Z": _ZEROS,
            "_U32": _U32,
            "_STR": string_bytes,
            "_STRS": strings_bytes,
        }
        self._n = 0

    def name(self, stem: str) -> str:
        self._n += 1
        return f"{stem}{self._n}"

    def const(self, stem: str, value: Any) -> str:
        name = self.name("_" + stem)
        self.env[name] = value
        return name

    def add(self, indent: int, line: str) -> None:
        self.lines.append("    " * indent + line)

    def function(self, header: str) -> Callable[..., Any]:
        text = "\n".join([header, *self.lines])
        namespace: dict[str, Any] = {}
        exec(compile(text, "<dds_wire>", "exec"), self.env, namespace)
        return namespace[header.split()[1].split("(")[0]]


def _compile(ros_type: str) -> tuple[Callable[[Any], bytes], Callable[[bytes], Any]]:
    enc = _Source()
    enc.add(1, "buf = bytearray(b'\\x00\\x01\\x00\\x00')")
    _encode_struct(enc, ros_type, "sample", 1)
    enc.add(1, "buf += _Z[-len(buf) & 3]")  # Cyclone pads a sample to 4 bytes
    enc.add(1, "return bytes(buf)")
    return enc.function("def encode(sample):"), _decoder(ros_type, None)


def _decoder(ros_type: str, hub: type | None) -> Callable[[bytes], Any]:
    dec = _Source()
    dec.add(1, "p = 4")
    dec.add(1, "size = len(data)")
    result = _decode_struct(dec, ros_type, 1, hub)
    dec.add(1, f"return {result}")
    return dec.function("def decode(data):")


def _fields(ros_type: str) -> list[tuple[str, Any]]:
    return list(ros2_fielddefs()[ros_type][1])


def _align(src: _Source, indent: int, size: int, *, decoding: bool) -> None:
    if size == 1:
        return
    mask = size - 1
    if decoding:
        src.add(indent, f"p += (4 - p) & {mask}")
    else:
        src.add(indent, f"buf += _Z[(4 - len(buf)) & {mask}]")


def _zero(base: str) -> str:
    return {"string": "''", "bool": "False", "float32": "0.0", "float64": "0.0"}.get(base, "0")


def _encode_struct(src: _Source, ros_type: str, expr: str, indent: int) -> None:
    """Fields by name from any object; a missing or None field is the type's zero."""
    for field, desc in _fields(ros_type):
        var = src.name("v")
        src.add(indent, f"{var} = getattr({expr}, {field!r}, None)")
        _encode_value(src, desc, var, indent)


def _encode_value(src: _Source, desc: tuple[Any, Any], var: str, indent: int) -> None:
    kind, detail = desc
    if kind == Nodetype.BASE:
        base, bound = detail
        src.add(indent, f"if {var} is None:")
        src.add(indent + 1, f"{var} = {_zero(base)}")
        if base == "string" and not bound:
            _align(src, indent, 4, decoding=False)
            src.add(indent, f"buf += _STR({var})")
            return
        if base == "string":
            text = src.name("t")
            src.add(indent, f"{text} = {var}.encode()")
            if bound:
                src.add(indent, f"if len({text}) > {bound}:")
                src.add(indent + 1, f"raise ValueError('string longer than its bound {bound}')")
            _align(src, indent, 4, decoding=False)
            src.add(indent, f"buf += _U32.pack(len({text}) + 1)")
            src.add(indent, f"buf += {text}")
            src.add(indent, "buf += b'\\x00'")
            return
        fmt = _FORMATS[base]
        packer = src.const("S", struct.Struct("<" + fmt))
        _align(src, indent, struct.calcsize(fmt), decoding=False)
        src.add(indent, f"buf += {packer}.pack({var})")
        return
    if kind == Nodetype.NAME:
        if detail in _STAMPS:
            # Hub stamps are float seconds; a Cyclone sample has sec/nanosec.
            src.env.update(_split=split_seconds, _STAMP=struct.Struct("<iI"))
            sec, nsec = src.name("s"), src.name("ns")
            src.add(indent, f"if {var} is None:")
            src.add(indent + 1, f"{sec}, {nsec} = 0, 0")
            src.add(indent, f"elif isinstance({var}, (int, float)):")
            src.add(indent + 1, f"{sec}, {nsec} = _split({var}, {_STAMPS[detail]!r})")
            src.add(indent, "else:")
            src.add(indent + 1, f"{sec}, {nsec} = {var}.sec, {var}.nanosec")
            _align(src, indent, 4, decoding=False)
            src.add(indent, f"buf += _STAMP.pack({sec}, {nsec})")
            return
        src.add(indent, f"if {var} is None:")
        src.add(indent + 1, f"{var} = {src.const('D', dds_type(detail)())}")
        _encode_struct(src, detail, var, indent)
        return
    element, size = detail
    src.add(indent, f"if {var} is None:")
    src.add(indent + 1, f"{var} = ()")
    if kind != Nodetype.ARRAY and element[0] == Nodetype.BASE and element[1] == ("string", 0):
        if size:
            src.add(indent, f"if len({var}) > {size}:")
            src.add(indent + 1, f"raise ValueError('sequence longer than its bound {size}')")
        _align(src, indent, 4, decoding=False)
        src.add(indent, f"buf += _STRS({var} if type({var}) is tuple else tuple({var}))")
        return
    if kind == Nodetype.ARRAY:
        src.add(indent, f"if len({var}) != {size}:")
        src.add(indent + 1, f"raise ValueError(f'array of {size} items has {{len({var})}}')")
    else:
        if size:
            src.add(indent, f"if len({var}) > {size}:")
            src.add(indent + 1, f"raise ValueError('sequence longer than its bound {size}')")
        _align(src, indent, 4, decoding=False)
        src.add(indent, f"buf += _U32.pack(len({var}))")
    if element[0] == Nodetype.BASE and element[1][0] != "string":
        fmt = _FORMATS[element[1][0]]
        if struct.calcsize(fmt) > 1:
            src.add(indent, f"if {var}:")
            _align(src, indent + 1, struct.calcsize(fmt), decoding=False)
        src.add(indent, f"buf += struct.pack(f'<{{len({var})}}{fmt}', *{var})")
        src.env["struct"] = struct
        return
    item = src.name("e")
    src.add(indent, f"for {item} in {var}:")
    _encode_value(src, element, item, indent + 1)


def _decode_struct(src: _Source, ros_type: str, indent: int, hub: type | None) -> str:
    """Emit code reading ``ros_type`` at ``p``; return the expression building it.

    Without ``hub`` the result is the Cyclone sample; with it, the hub dataclass,
    given the fields it shares with the type (by name, converted as its hints say).
    """
    if hub is None:
        values = [_decode_value(src, desc, indent, None, "") for _f, desc in _fields(ros_type)]
        return f"{src.const('C', dds_type(ros_type))}({', '.join(values)})"
    hints = typing.get_type_hints(hub)
    fields = {f.name: f for f in dataclasses.fields(hub)}
    given: dict[str, str] = {}
    for name, desc in _fields(ros_type):
        wanted = name in fields
        value = _decode_value(
            src, desc, indent, hints[name] if wanted else None, f"{ros_type}.{name}"
        )
        if wanted:
            given[name] = value
    for name, f in fields.items():
        if name not in given:  # a field the DDS type lacks: its default
            if f.default_factory is not dataclasses.MISSING:
                given[name] = f"{src.const('F', f.default_factory)}()"
            else:
                given[name] = src.const("d", f.default)
    # A frozen dataclass's __init__ sets each field through object.__setattr__, the
    # largest part of a decode; a message decoded here is new and not yet shared, so
    # its fields are filled in at once (hub messages have no __post_init__).
    made = src.name("o")
    src.env["_new"] = object.__new__
    src.add(indent, f"{made} = _new({src.const('H', hub)})")
    args = ", ".join(f"{name}={value}" for name, value in given.items())
    src.add(indent, f"{made}.__dict__.update({args})")
    return made


def _check_number(src: _Source, indent: int, var: str, hint: Any, label: str) -> str:
    """Emit the checks of a number a foreign writer may get wrong; return its hub value."""
    if isinstance(hint, type) and issubclass(hint, enum.IntEnum):
        members = src.const("M", {m.value: m for m in hint})
        known = ", ".join(f"{m.name}={m.value}" for m in hint)
        member = src.name("m")
        src.add(indent, f"{member} = {members}.get({var})")
        src.add(indent, f"if {member} is None:")
        src.add(indent + 1, f"raise ValueError(f'{label} is {{{var}!r}}, not one of {known}')")
        return member
    if hint is float:
        src.env["_isfinite"] = math.isfinite
        src.add(indent, f"if not _isfinite({var}):")
        src.add(indent + 1, f"raise ValueError(f'{label} is {{{var}!r}}, not a finite number')")
    return var


def _decode_value(src: _Source, desc: tuple[Any, Any], indent: int, hint: Any, label: str) -> str:
    kind, detail = desc
    var = src.name("v")
    if kind == Nodetype.BASE:
        base = detail[0]
        if base == "string":
            n = src.name("n")
            _align(src, indent, 4, decoding=True)
            src.add(indent, f"{n} = _U32.unpack_from(data, p)[0]")
            src.add(indent, f"p += 4 + {n}")
            src.add(indent, f"if {n} == 0 or p > size:")
            src.add(indent + 1, "raise ValueError(f'string length {" + n + "} past the end')")
            src.add(indent, f"{var} = data[p - {n}:p - 1].decode()")
            return var
        fmt = _FORMATS[base]
        unpacker = src.const("S", struct.Struct("<" + fmt))
        _align(src, indent, struct.calcsize(fmt), decoding=True)
        src.add(indent, f"{var} = {unpacker}.unpack_from(data, p)[0]")
        src.add(indent, f"p += {struct.calcsize(fmt)}")
        return _check_number(src, indent, var, hint, label)
    if kind == Nodetype.NAME:
        if hint is not None and detail in _STAMPS:
            src.env["_STAMP"] = struct.Struct("<iI")
            _align(src, indent, 4, decoding=True)
            src.add(indent, f"{var} = _STAMP.unpack_from(data, p)")
            src.add(indent, "p += 8")
            src.add(indent, f"{var} = float({var}[0] + {var}[1] * 1e-9)")
            return var
        nested = hint if isinstance(hint, type) else None
        src.add(indent, f"{var} = {_decode_struct(src, detail, indent, nested)}")
        return var
    element, size = detail
    count = src.name("n")
    if kind == Nodetype.ARRAY:
        src.add(indent, f"{count} = {size}")
    else:
        _align(src, indent, 4, decoding=True)
        src.add(indent, f"{count} = _U32.unpack_from(data, p)[0]")
        src.add(indent, "p += 4")
        src.add(indent, f"if {count} > size - p:")
        src.add(indent + 1, "raise ValueError(f'sequence of {" + count + "} items past the end')")
    item_hint = (typing.get_args(hint) or (None,))[0] if hint is not None else None
    as_hub = "tuple" if hint is not None else "list"
    if element[0] == Nodetype.BASE and element[1][0] != "string" and item_hint in (None, float):
        fmt = _FORMATS[element[1][0]]
        width = struct.calcsize(fmt)
        src.env["struct"] = struct
        if width > 1:
            src.add(indent, f"if {count}:")
            _align(src, indent + 1, width, decoding=True)
        kind_of = "bytes" if hint is bytes else as_hub
        src.add(indent, f"{var} = {kind_of}(struct.unpack_from(f'<{{{count}}}{fmt}', data, p))")
        src.add(indent, f"p += {count} * {width}")
        if item_hint is float:
            src.env["_isfinite"] = math.isfinite
            src.add(indent, f"if not all(map(_isfinite, {var})):")
            src.add(indent + 1, f"raise ValueError('{label} holds a number that is not finite')")
        return var
    items = src.name("items")
    src.add(indent, f"{items} = []")
    src.add(indent, f"for _ in range({count}):")
    item = _decode_value(src, element, indent + 1, item_hint, label)
    src.add(indent + 1, f"{items}.append({item})")
    src.add(indent, f"{var} = {as_hub}({items})")
    return var
