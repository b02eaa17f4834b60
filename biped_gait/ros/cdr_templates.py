"""Messages of a fixed shape serialized many at a time: rclpy serializes a message once, and
its numbers are then written in place into copies of those bytes.

A message of a fixed shape has the same strings and sequence lengths every time (the joint
names, the frame ids, the covariances), so its CDR bytes differ from one instance to the next
only where its numbers are. A ``CdrTemplate`` finds those places by serializing, with rclpy's
``serialize_message`` (``cdr.serialized``), the message its ``build`` function makes of marker values, and checks
them by comparing its own bytes of random values with rclpy's. ``encode`` then writes the
numbers of many messages (one per row) into as many copies of the template at once. The bytes
are those rclpy gives, to the bit of every field (``CdrTemplate`` refuses a message for which
they are not); only the alignment padding between fields, which rclpy's serializer leaves as it
finds it in memory, is that of the template.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from rclpy.serialization import deserialize_message

from .cdr import HEADER, serialized

_FLOAT_MARK = -1.2345678901234567e-123  # times 1, 2, ...: float64 markers
_INT_MARK = 0x5EC0_1A00  # plus 0, 1, ...: uint32 markers
Build = Callable[[np.ndarray, np.ndarray], object]


class CdrTemplate:
    """Serialized messages made by ``build(floats, ints)``: ``floats`` (``n_floats`` float64
    values) and ``ints`` (``n_ints`` values stored as int32 or uint32, each possibly in several
    fields, e.g. a stamp repeated in every transform) placed as they are in the message's fields.
    ``ValueError`` if a value is not found where rclpy puts it, or the bytes do not decode to
    the message ``build`` makes."""

    def __init__(self, build: Build, n_floats: int, n_ints: int = 0) -> None:
        self.n_floats, self.n_ints = n_floats, n_ints
        floats = _FLOAT_MARK * np.arange(1, n_floats + 1)
        ints = _INT_MARK + np.arange(n_ints)
        marked = build(floats, ints)
        self.template = np.frombuffer(serialized(marked), dtype=np.uint8)
        body = self.template[HEADER:]
        self._float_bytes = np.concatenate(
            [_where(body, value.tobytes(), 8, once=True) for value in floats.astype("<f8")] or [np.zeros(0, int)])
        self._int_bytes = [_where(body, int(value).to_bytes(4, "little"), 4) for value in ints]
        rng = np.random.default_rng(0)
        check_floats, check_ints = rng.normal(size=n_floats), rng.integers(0, 2**31, n_ints)
        encoded = self.encode(check_floats[None], check_ints[None])[0].tobytes()
        expected = build(check_floats, check_ints)
        if len(encoded) != len(serialized(expected)) or deserialize_message(encoded, type(marked)) != expected:
            raise ValueError("the message's bytes do not follow its values: not a message of a fixed shape")

    @property
    def size(self) -> int:
        """Bytes of one serialized message."""
        return len(self.template)

    def encode(self, floats: np.ndarray, ints: np.ndarray | None = None) -> np.ndarray:
        """The serialized messages of the rows of ``floats`` (n x n_floats) and ``ints`` (n x
        n_ints), as the rows of an n x ``size`` array of bytes."""
        floats = np.ascontiguousarray(np.atleast_2d(floats), dtype="<f8")
        if floats.shape[1:] != (self.n_floats,):
            raise ValueError(f"expected rows of {self.n_floats} floats, got shape {floats.shape}")
        out = np.tile(self.template, (len(floats), 1))
        out[:, self._float_bytes] = floats.view(np.uint8)
        if self.n_ints:
            ints = np.asarray(ints, dtype=np.int64).reshape(len(floats), self.n_ints)
            words = ints.astype("<u4").view(np.uint8).reshape(len(floats), self.n_ints, 4)
            for k, places in enumerate(self._int_bytes):
                out[:, places] = np.tile(words[:, k], len(places) // 4)
        return out


def _where(body: np.ndarray, pattern: bytes, align: int, once: bool = False) -> np.ndarray:
    """The byte indices (in the whole message, encapsulation header included) of every aligned
    occurrence of ``pattern`` in ``body``; ``ValueError`` if there is none (or more than one
    with ``once``)."""
    data = body.tobytes()
    starts, at = [], data.find(pattern)
    while at >= 0:
        if at % align == 0:
            starts.append(at)
        at = data.find(pattern, at + 1)
    if not starts or (once and len(starts) > 1):
        raise ValueError(f"a value of the message was found {len(starts)} times in its bytes")
    return np.concatenate([HEADER + s + np.arange(len(pattern)) for s in starts])
