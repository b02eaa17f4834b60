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
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path

import yaml
from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import Writer as RawWriter

from .metadata import TopicRecord, write_metadata
from .schemas import schema_text

DEFAULT_CHUNK_SIZE = 64 * 1024


@dataclass
class _Channel:
    id: int
    record: TopicRecord


class McapRecorder:
    """Write serialized messages to ``directory/name/name_0.mcap``; ``close`` adds metadata.yaml."""

    def __init__(self, directory: str | Path, name: str, chunk_size: int = DEFAULT_CHUNK_SIZE) -> None:
        self.bag_dir = Path(directory) / name
        self.bag_dir.mkdir(parents=True, exist_ok=False)
        self.path = self.bag_dir / f"{name}_0.mcap"
        self._file = open(self.path, "wb")
        self._writer = RawWriter(self._file, chunk_size=chunk_size)
        self._writer.start(profile="ros2", library="biped_gait")
        self._channels: dict[str, _Channel] = {}
        self._schemas: dict[str, int] = {}
        self._lock = threading.Lock()
        self._first: int | None = None
        self._last: int | None = None
        self.closed = False

    def add_topic(self, topic: str, datatype: str, qos: list[dict], type_hash: str = "") -> None:
        """Register ``topic`` of type ``datatype`` ('pkg/msg/Type') with the QoS profiles its
        publishers offer (rosbag2 dictionaries, ``qos.qos_description``), as rosbag2 does: the
        schema once per type, the channel with its QoS in its metadata. Idempotent."""
        with self._lock:
            if topic in self._channels or self.closed:
                return
            schema = self._schemas.get(datatype)
            if schema is None:
                text = schema_text(datatype)
                schema = self._schemas[datatype] = self._writer.register_schema(datatype, SchemaEncoding.ROS2, text.encode())
            channel = self._writer.register_channel(
                topic, MessageEncoding.CDR, schema, metadata={"offered_qos_profiles": yaml.safe_dump(qos)}
            )
            self._channels[topic] = _Channel(channel, TopicRecord(datatype, 0, list(qos), type_hash))

    def write(self, topic: str, data: bytes, stamp_ns: int | None = None) -> None:
        """Record the CDR bytes ``data`` on the registered ``topic`` at ``stamp_ns`` (default:
        now, ns since the epoch); nothing once closed."""
        stamp = time.time_ns() if stamp_ns is None else int(stamp_ns)
        with self._lock:
            if self.closed:
                return
            entry = self._channels[topic]
            self._writer.add_message(entry.id, log_time=stamp, data=data, publish_time=stamp,
                                     sequence=entry.record.count)
            self._file.flush()  # a closed chunk reaches the disk now, not when Python's buffer fills
            entry.record.count += 1
            self._first = stamp if self._first is None else min(self._first, stamp)
            self._last = stamp if self._last is None else max(self._last, stamp)

    def close(self) -> None:
        """Finalize the MCAP file (index, summary) and write metadata.yaml. Idempotent."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
            self._writer.finish()
            self._file.close()
            write_metadata(self.bag_dir, self.path.name, self._first or 0, self._last or 0,
                           {topic: entry.record for topic, entry in self._channels.items()})
