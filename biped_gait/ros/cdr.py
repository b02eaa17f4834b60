"""The CDR bytes of a message, exactly as long as the message.

rclpy's ``serialize_message`` (over rmw_fastrtps) returns as many bytes as its size estimate,
and the estimate aligns the elements of an *empty* sequence of 8-byte numbers as if it had one:
a message with an empty ``float64[]`` that starts 4 bytes past an 8-byte boundary comes out 4
bytes longer than its CDR (XCDR1) encoding, with uninitialized bytes at the end. Readers that
check the length (rosbags: "CDR message size mismatch") refuse such bytes. ``serialized``
returns rclpy's bytes cut to the encoding's length, which ``cdr_size`` computes from the
message's fields (alignment counted from the end of the 4-byte encapsulation header, as CDR
does; an empty sequence aligns nothing).
"""

from __future__ import annotations

import re
from functools import lru_cache

from rclpy.serialization import serialize_message

HEADER = 4  # bytes of the CDR encapsulation header
_PRIMITIVE_SIZES = {
    "boolean": 1, "octet": 1, "char": 1, "uint8": 1, "int8": 1,
    "int16": 2, "uint16": 2, "int32": 4, "uint32": 4, "float": 4,
    "int64": 8, "uint64": 8, "double": 8,
}
_ARRAY = re.compile(r"(.+)\[(\d+)\]")


def serialized(msg) -> bytes:
    """The CDR bytes of the ROS message ``msg`` (encapsulation header included), rclpy's
    encoding without the bytes its size estimate adds past the end."""
    data = serialize_message(msg)
    size = HEADER + cdr_size(msg)
    if size > len(data):
        raise RuntimeError(f"{type(msg).__name__}: computed {size} CDR bytes, rclpy wrote {len(data)}")
    return data[:size]


def cdr_size(msg) -> int:
    """Bytes of the CDR body of ``msg`` (after the encapsulation header)."""
    return _message_end(0, msg)


def _message_end(pos: int, msg) -> int:
    for name, typ in _fields(type(msg)):
        pos = _value_end(pos, getattr(msg, name), typ)
    return pos


@lru_cache(maxsize=None)
def _fields(cls: type) -> tuple[tuple[str, str], ...]:
    return tuple(cls.get_fields_and_field_types().items())


def _align(pos: int, size: int) -> int:
    return (pos + size - 1) & -size


def _value_end(pos: int, value, typ: str) -> int:
    if typ.startswith("sequence<"):
        inner = typ[len("sequence<"):-1].split(",")[0].strip()
        return _items_end(_align(pos, 4) + 4, value, inner, len(value))
    array = _ARRAY.fullmatch(typ)
    if array:
        return _items_end(pos, value, array.group(1), int(array.group(2)))
    if typ == "string" or typ.startswith("string<"):
        return _align(pos, 4) + 4 + len(value.encode()) + 1
    if typ in _PRIMITIVE_SIZES:
        size = _PRIMITIVE_SIZES[typ]
        return _align(pos, size) + size
    if "/" in typ:
        return _message_end(pos, value)
    raise TypeError(f"CDR size of a field of type {typ!r} is not known here")


def _items_end(pos: int, values, inner: str, count: int) -> int:
    if count == 0:
        return pos
    if inner in _PRIMITIVE_SIZES:
        size = _PRIMITIVE_SIZES[inner]
        return _align(pos, size) + size * count
    for value in values:
        pos = _value_end(pos, value, inner)
    return pos
