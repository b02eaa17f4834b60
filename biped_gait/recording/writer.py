"""Recording serialized ROS 2 messages to MCAP (ROS 2 profile: ``ros2msg`` schemas, CDR
messages) as a rosbag2 directory ``<dir>/<name>/`` holding ``<name>_0.mcap`` and
``metadata.yaml``. No ROS code: the caller hands in CDR bytes (what a publisher sends, or a
``raw=True`` subscription receives) and the type's name.

rclpy's ``serialize_message`` appends padding after a message that ends in an empty
``float64[]`` sequence (its size estimate aligns the empty sequence); strict readers (rosbags)
refuse such bytes, so the project's messages fill those sequences (zero joint efforts in the
ballistic phase) and a test decodes every recorded message with rosbags.

Chunks are bounded by size (``chunk_size`` bytes) and each closed chunk is flushed to the file
at once, so a killed process loses at most its open chunk; ``recover`` rebuilds a complete file
(index and summary) from what a killed writer left. ``close`` finalizes the file; the nodes call
it on SIGINT and SIGTERM. Thread-safe: callbacks of a multi-threaded executor may write at once.

Failures (a full disk, a folder that cannot be created, a bag folder deleted while recording)
raise ``RecordingError`` with a one-line message, once; the recorder then stops recording and
finishes the file as far as it got. So that a full disk still leaves room to finish it, the
recorder holds a reserve file (``.space_reserve``, two chunks and 256 kB) in the bag folder from
the start and frees it when a write fails or at ``close``.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import Writer as RawWriter

from .metadata import TopicRecord, write_metadata
from .schemas import schema_text, type_hash as installed_type_hash
from .sink import FileSink, Opener, open_unbuffered

DEFAULT_CHUNK_SIZE = 64 * 1024
Message = tuple[str, bytes, int]  # topic, CDR bytes, stamp (ns since the epoch)
RESERVE_NAME = ".space_reserve"
RESERVE_MARGIN = 256 * 1024  # bytes beyond two chunks: the summary and metadata.yaml


class RecordingError(OSError):
    """Recording failed (disk full, folder not writable or deleted); the message is one line."""


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc) or type(exc).__name__


@dataclass
class _Channel:
    id: int
    record: TopicRecord


@dataclass(frozen=True, eq=False)
class SampleRows:
    """Samples of several topics taken together, as rows: sample ``k`` is one message per topic,
    the CDR bytes ``rows[i][k]`` on ``topics[i]``, all at ``stamps[k]`` (ns since the epoch).
    Recorded in sample order, the topics in their order within a sample, as if written one by
    one; handed over as arrays, so that a step of samples costs its writer one call."""

    topics: tuple[str, ...]
    rows: tuple[np.ndarray, ...]  # per topic: n x (message size) uint8
    stamps: np.ndarray  # n, int64

    def messages(self) -> Iterator[Message]:
        """The messages, one by one, in recording order."""
        columns = [[row.tobytes() for row in rows] for rows in self.rows]
        for k, stamp in enumerate(self.stamps.tolist()):
            for topic, column in zip(self.topics, columns):
                yield topic, column[k], stamp


def _each_message(items: Iterable[Message | SampleRows]) -> Iterator[Message]:
    for item in items:
        if isinstance(item, SampleRows):
            yield from item.messages()
        else:
            yield item


class McapRecorder:
    """Write serialized messages to ``directory/name/name_0.mcap``; ``close`` adds metadata.yaml.
    ``opener`` opens the MCAP file (unbuffered binary; tests inject one that fails).
    ``FileExistsError`` if the bag folder exists; ``RecordingError`` if it cannot be made."""

    def __init__(self, directory: str | Path, name: str, chunk_size: int = DEFAULT_CHUNK_SIZE,
                 opener: Opener = open_unbuffered) -> None:
        self.bag_dir = Path(directory) / name
        self.path = self.bag_dir / f"{name}_0.mcap"
        self._reserve = self.bag_dir / RESERVE_NAME
        try:
            self.bag_dir.mkdir(parents=True, exist_ok=False)
        except FileExistsError:
            raise
        except OSError as exc:
            raise RecordingError(f"recording failed: cannot create {self.bag_dir}: {_reason(exc)}") from None
        try:
            with open(self._reserve, "wb") as reserve:
                os.posix_fallocate(reserve.fileno(), 0, 2 * chunk_size + RESERVE_MARGIN)
            self._sink = FileSink(self.path, opener)
            self._writer = RawWriter(self._sink, chunk_size=chunk_size)
            self._writer.start(profile="ros2", library="biped_gait")
            self._sink.flush()
        except OSError as exc:
            self._release_reserve()
            raise RecordingError(f"recording failed: cannot write in {self.bag_dir}: {_reason(exc)}") from None
        self._channels: dict[str, _Channel] = {}
        self._schemas: dict[str, int] = {}
        self._lock = threading.Lock()
        self._first: int | None = None
        self._last: int | None = None
        self.closed = False
        self.failure = ""  # why recording stopped early ("" while it goes on or closed cleanly)

    def add_topic(self, topic: str, datatype: str, qos: list[dict], type_hash: str | None = None) -> None:
        """Register ``topic`` of type ``datatype`` ('pkg/msg/Type') with the QoS profiles its
        publishers offer (rosbag2 dictionaries, ``qos.qos_description``) and its type description
        hash (None: the installed type description's), as rosbag2 does: the schema once per type,
        the channel with its QoS and type hash in its metadata. Idempotent."""
        if type_hash is None:
            type_hash = installed_type_hash(datatype)
        with self._lock:
            if topic in self._channels or self.closed:
                return
            schema = self._schemas.get(datatype)
            if schema is None:
                text = schema_text(datatype)
                schema = self._schemas[datatype] = self._writer.register_schema(datatype, SchemaEncoding.ROS2, text.encode())
            metadata = {"offered_qos_profiles": yaml.safe_dump(qos)}
            if type_hash:
                metadata["topic_type_hash"] = type_hash
            channel = self._writer.register_channel(topic, MessageEncoding.CDR, schema, metadata=metadata)
            self._channels[topic] = _Channel(channel, TopicRecord(datatype, 0, list(qos), type_hash))

    def write(self, topic: str, data: bytes, stamp_ns: int | None = None) -> None:
        """Record the CDR bytes ``data`` on the registered ``topic`` at ``stamp_ns`` (default:
        now, ns since the epoch); nothing once closed. ``RecordingError`` (once) if the file
        cannot take it: the recorder has then finished the file as far as it got."""
        self.write_many([(topic, data, time.time_ns() if stamp_ns is None else int(stamp_ns))])

    def write_many(self, messages: list[Message | SampleRows]) -> None:
        """Record ``messages`` ((topic, CDR bytes, stamp in ns since the epoch), or rows of
        samples), in this order, each chunk they close handed to the file at once; as ``write``
        otherwise."""
        with self._lock:
            if self.closed or not messages:
                return
            add, channels, sink = self._writer.add_message, self._channels, self._sink
            for topic, data, stamp in _each_message(messages):
                entry = channels[topic]
                add(entry.id, log_time=stamp, data=data, publish_time=stamp, sequence=entry.record.count)
                entry.record.count += 1
                self._first = stamp if self._first is None or stamp < self._first else self._first
                self._last = stamp if self._last is None or stamp > self._last else self._last
                if sink.pending:
                    self._flush()

    def _flush(self) -> None:
        """Hand the closed chunk to the file; ``_fail`` if the file refuses or was deleted."""
        written = self._sink.written
        try:
            self._sink.flush()
        except OSError as exc:
            self._fail(_reason(exc))
        if self._sink.written != written and self._sink.deleted:
            self._fail(f"{self.bag_dir} was deleted while recording")

    def _fail(self, reason: str) -> None:
        """Stop recording: free the reserve, finish the file as far as it got, and raise."""
        self.failure = f"recording failed: {self.path}: {reason}"
        self.closed = True
        self._release_reserve()
        unfinished = self._finish()
        if unfinished:
            self.failure += f"; {unfinished}"
        raise RecordingError(self.failure)

    def _finish(self) -> str:
        """Finish the MCAP file and write metadata.yaml; '' or what could not be done."""
        try:
            self._writer.finish()
            self._sink.flush()
        except OSError as exc:
            self._sink.close()
            return f"the file could not be finished ({_reason(exc)}): 'biped-gait recover' rebuilds what it holds"
        self._sink.close()
        try:
            write_metadata(self.bag_dir, self.path.name, self._first or 0, self._last or 0,
                           {topic: entry.record for topic, entry in self._channels.items()})
        except OSError as exc:
            return f"metadata.yaml could not be written ({_reason(exc)})"
        return ""

    def _release_reserve(self) -> None:
        try:
            self._reserve.unlink()
        except OSError:
            pass  # already gone (or the folder is)

    def close(self) -> None:
        """Finalize the MCAP file (index, summary) and write metadata.yaml. Idempotent.
        ``RecordingError`` if that fails (the folder deleted, the disk full beyond the reserve)."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
            self._release_reserve()
            if self._sink.deleted:
                self._sink.close()
                self.failure = f"recording failed: {self.bag_dir} was deleted while recording"
                raise RecordingError(self.failure)
            unfinished = self._finish()
            if unfinished:
                self.failure = f"recording failed: {self.path}: {unfinished}"
                raise RecordingError(self.failure)
