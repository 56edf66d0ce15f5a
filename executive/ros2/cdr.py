"""Decode ROS 2 messages from CDR (the bytes on the DDS wire) into plain Python values.

A decoded message is the dict shape observers read from dura's own bus: a dict per
message (field name -> value), lists for arrays and sequences, ``int``, ``float``,
``bool`` and ``str`` for the rest. So ``header.stamp.sec``, ``ranges.0`` and
``twist.twist.linear.x`` name the same values as on a JSON payload.

The encoding is XCDR version 1, as ROS 2 uses it: a 4-byte encapsulation header (big
or little endian), then every primitive aligned to its size, counted from the end of
the header (8-byte values to 8). A decoder is compiled once per type from its field
definitions; a structure of primitives only is read with one ``struct`` call per
alignment it can start at. Every problem (too short, a count running past the end,
bad UTF-8, an unknown encapsulation) is a :class:`CdrError`.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Mapping
from typing import Any

from rosbags.interfaces import Nodetype

Reader = Callable[[memoryview, int], tuple[Any, int]]
FieldDefs = Mapping[str, tuple[Any, list[tuple[str, tuple[Any, Any]]]]]

CODES = {
    "bool": "?", "byte": "B", "char": "B", "int8": "b", "uint8": "B", "int16": "h",
    "uint16": "H", "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q",
    "float32": "f", "float64": "d",
}  # fmt: skip
_ENCAPSULATIONS = {b"\x00\x00": ">", b"\x00\x01": "<"}  # CDR_BE, CDR_LE


class CdrError(ValueError):
    """Bytes that are not a CDR encoding of the expected type."""


class Decoder:
    """Decodes one message type from CDR bytes (both byte orders)."""

    def __init__(self, fielddefs: FieldDefs, ros_type: str) -> None:
        self.type = ros_type
        self._readers = {order: _Compiler(fielddefs, order).struct(ros_type) for order in "<>"}

    def __call__(self, raw: bytes) -> dict[str, Any]:
        """Decode a message into a dict.

        Raises:
            CdrError: malformed bytes.
        """
        return self.decode(raw)[0]

    def exact(self, raw: bytes) -> dict[str, Any]:
        """Decode a message that fills the bytes (up to 3 bytes of padding may follow).

        Raises:
            CdrError: malformed bytes, or bytes left over (another definition wrote them).
        """
        value, left = self.decode(raw)
        if left > 3:
            raise CdrError(f"{left} bytes left over after a {self.type}")
        return value

    def decode(self, raw: bytes) -> tuple[dict[str, Any], int]:
        """Decode a message; return it and how many bytes followed it."""
        order = _ENCAPSULATIONS.get(bytes(raw[:2]))
        if order is None or len(raw) < 4:
            raise CdrError(f"not plain CDR (encapsulation {bytes(raw[:4]).hex() or 'missing'})")
        buf = memoryview(raw)[4:]
        try:
            value, end = self._readers[order](buf, 0)
        except (struct.error, UnicodeDecodeError, IndexError, CdrError) as e:
            raise CdrError(f"not a {self.type}: {e}") from e
        return value, len(buf) - end


def _count(buf: memoryview, pos: int, order: str) -> tuple[int, int]:
    """Read a sequence's or string's length (uint32, aligned to 4); return it and the next position."""
    pos += -pos % 4
    (n,) = struct.unpack_from(order + "I", buf, pos)
    if n > len(buf) - pos - 4:
        raise CdrError(f"a length of {n} at byte {pos} runs past the end ({len(buf)} bytes)")
    return n, pos + 4


class _Compiler:
    """Builds the readers of one byte order, each type's once."""

    def __init__(self, fielddefs: FieldDefs, order: str) -> None:
        self.fielddefs = fielddefs
        self.order = order
        self.structs: dict[str, Reader] = {}

    def struct(self, name: str) -> Reader:
        reader = self.structs.get(name)
        if reader is not None:
            return reader
        if name not in self.fielddefs:
            raise CdrError(f"unknown message type '{name}'")
        fields = self.fielddefs[name][1]
        if all(d[0] == Nodetype.BASE and d[1][0] in CODES for _, d in fields):
            reader = self._flat([f for f, _ in fields], [CODES[d[1][0]] for _, d in fields])
        else:
            reader = self._nested([(f, self.field(d)) for f, d in fields])
        self.structs[name] = reader
        return reader

    def field(self, desc: tuple[Any, Any]) -> Reader:
        kind, details = desc
        if kind == Nodetype.BASE:
            return self._string() if details[0] == "string" else self._primitive(CODES[details[0]])
        if kind == Nodetype.NAME:
            return self.struct(details)
        inner, size = details
        code = CODES.get(inner[1][0]) if inner[0] == Nodetype.BASE else None
        if kind == Nodetype.ARRAY:
            return self._primitives(code, size) if code else self._many(self.field(inner), size)
        return self._primitives(code, None) if code else self._many(self.field(inner), None)

    def _primitive(self, code: str) -> Reader:
        unpack = struct.Struct(self.order + code).unpack_from
        size = struct.calcsize(code)

        def read(buf: memoryview, pos: int) -> tuple[Any, int]:
            pos += -pos % size
            return unpack(buf, pos)[0], pos + size

        return read

    def _string(self) -> Reader:
        order = self.order

        def read(buf: memoryview, pos: int) -> tuple[Any, int]:
            n, pos = _count(buf, pos, order)
            # the length counts the terminating NUL, which is not part of the text
            return (str(buf[pos : pos + n - 1], "utf-8") if n else ""), pos + n

        return read

    def _flat(self, names: list[str], codes: list[str]) -> Reader:
        """Read a structure of primitives with one unpack, laid out for where it starts."""
        layouts: dict[int, tuple[Callable[[memoryview, int], tuple[Any, ...]], int]] = {}
        order = self.order

        def layout(start: int) -> tuple[Callable[[memoryview, int], tuple[Any, ...]], int]:
            text, pos = order, start
            for code in codes:
                size = struct.calcsize(code)
                text += "x" * (-pos % size) + code
                pos += -pos % size + size
            return struct.Struct(text).unpack_from, pos - start

        def read(buf: memoryview, pos: int) -> tuple[Any, int]:
            found = layouts.get(pos & 7)
            if found is None:
                found = layouts[pos & 7] = layout(pos & 7)
            unpack, length = found
            return dict(zip(names, unpack(buf, pos), strict=True)), pos + length

        return read

    @staticmethod
    def _nested(fields: list[tuple[str, Reader]]) -> Reader:
        def read(buf: memoryview, pos: int) -> tuple[Any, int]:
            out: dict[str, Any] = {}
            for name, reader in fields:
                out[name], pos = reader(buf, pos)
            return out, pos

        return read

    def _primitives(self, code: str, size: int | None) -> Reader:
        """Read an array (``size``) or a sequence (``None``: counted) of primitives."""
        order = self.order
        width = struct.calcsize(code)

        def read(buf: memoryview, pos: int) -> tuple[Any, int]:
            if size is None:
                n, pos = _count(buf, pos, order)
            else:
                n = size
            if n == 0:
                return [], pos
            pos += -pos % width
            return list(struct.unpack_from(f"{order}{n}{code}", buf, pos)), pos + n * width

        return read

    def _many(self, element: Reader, size: int | None) -> Reader:
        """Read an array or a sequence of strings or structures."""
        order = self.order

        def read(buf: memoryview, pos: int) -> tuple[Any, int]:
            if size is None:
                n, pos = _count(buf, pos, order)
            else:
                n = size
            out = []
            for _ in range(n):
                value, pos = element(buf, pos)
                out.append(value)
            return out, pos

        return read
