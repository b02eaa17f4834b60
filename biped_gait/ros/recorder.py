"""Recording rclpy messages to MCAP (ROS 2 profile: ``ros2msg`` schemas, CDR messages), as a
rosbag2-style directory ``<dir>/<name>/`` holding ``<name>_0.mcap`` and ``metadata.yaml``.

Chunks are bounded by size (``chunk_size`` bytes) and each closed chunk is flushed to the file
at once, so a killed process loses at most its open chunk; ``recover`` rebuilds a complete file (index and
summary) from what a killed writer left. ``close`` finalizes the file; the nodes call it on
SIGINT and SIGTERM. Thread-safe: callbacks of a multi-threaded executor may write at once.
"""

from __future__ import annotations

import array
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader
from mcap.records import Channel, Message, Schema
from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import Writer as RawWriter
from mcap_ros2._dynamic import serialize_dynamic  # the schema-driven CDR encoder of mcap-ros2-support

from .schemas import schema_text, type_name

DEFAULT_CHUNK_SIZE = 64 * 1024


@dataclass
class _Topic:
    channel: int
    encode: Callable[[object], bytes]
    type: str
    count: int = 0
    qos: list = field(default_factory=list)


class McapRecorder:
    """Write rclpy messages to ``directory/name/name_0.mcap``; ``close`` adds metadata.yaml."""

    def __init__(self, directory: str | Path, name: str, chunk_size: int = DEFAULT_CHUNK_SIZE) -> None:
        self.bag_dir = Path(directory) / name
        self.bag_dir.mkdir(parents=True, exist_ok=False)
        self.path = self.bag_dir / f"{name}_0.mcap"
        self._file = open(self.path, "wb")
        self._writer = RawWriter(self._file, chunk_size=chunk_size)
        self._writer.start(profile="ros2", library="biped_gait")
        self._topics: dict[str, _Topic] = {}
        self._schemas: dict[str, int] = {}
        self._lock = threading.Lock()
        self._first = None
        self._last = None
        self.closed = False

    def write(
        self, topic: str, msg, stamp_ns: int | None = None, transient_local: bool = False, datatype: str | None = None
    ) -> None:
        """Record ``msg`` on ``topic`` at ``stamp_ns`` (default: now, ns since the epoch).

        ``msg`` is an rclpy message, or a dict of its fields with ``datatype`` ('pkg/msg/Type')
        for a type that has no generated code here (tf2_msgs/msg/TFMessage).
        """
        stamp = time.time_ns() if stamp_ns is None else int(stamp_ns)
        with self._lock:
            if self.closed:
                return
            entry = self._topics.get(topic) or self._add_topic(topic, datatype or type_name(msg), transient_local)
            data = entry.encode(to_plain(msg))
            self._writer.add_message(entry.channel, log_time=stamp, data=data, publish_time=stamp, sequence=entry.count)
            self._file.flush()  # a closed chunk reaches the disk now, not when Python's buffer fills
            entry.count += 1
            self._first = stamp if self._first is None else min(self._first, stamp)
            self._last = stamp if self._last is None else max(self._last, stamp)

    def _add_topic(self, topic: str, datatype: str, transient_local: bool) -> _Topic:
        """Register the schema and the channel; the channel carries its QoS as rosbag2 does."""
        text = schema_text(datatype)
        schema = self._schemas.get(datatype)
        if schema is None:
            schema = self._schemas[datatype] = self._writer.register_schema(datatype, SchemaEncoding.ROS2, text.encode())
        qos = _latched_qos() if transient_local else []
        channel = self._writer.register_channel(
            topic, MessageEncoding.CDR, schema, metadata={"offered_qos_profiles": yaml.safe_dump(qos)}
        )
        encode = serialize_dynamic(datatype, text)[datatype]
        entry = self._topics[topic] = _Topic(channel, encode, datatype, qos=qos)
        return entry

    def close(self) -> None:
        """Finalize the MCAP file (index, summary) and write metadata.yaml. Idempotent."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
            self._writer.finish()
            self._file.close()
            write_metadata(self.bag_dir, self.path.name, self._first or 0, self._last or 0,
                           {t: (e.type, e.count, e.qos) for t, e in self._topics.items()})


def to_plain(value):
    """An rclpy message as nested dicts and lists, the form the MCAP CDR serializer takes
    (it refuses the numpy arrays that rclpy uses for fixed-size and numeric array fields)."""
    if hasattr(value, "get_fields_and_field_types"):
        return {name: to_plain(getattr(value, name)) for name in value.get_fields_and_field_types()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple, array.array)):
        return [to_plain(v) for v in value]
    return value


def _latched_qos() -> list[dict]:
    """rosbag2's description of a reliable, transient-local, keep-last-1 publisher."""
    infinite = lambda: {"sec": 2147483647, "nsec": 4294967295}  # noqa: E731  (fresh dicts: no YAML aliases)
    return [{
        "history": "keep_last", "depth": 1, "reliability": "reliable", "durability": "transient_local",
        "deadline": infinite(), "lifespan": infinite(), "liveliness": "automatic",
        "liveliness_lease_duration": infinite(), "avoid_ros_namespace_conventions": False,
    }]


def write_metadata(bag_dir: Path, filename: str, first: int, last: int, topics: dict[str, tuple[str, int, list]]) -> None:
    """rosbag2 ``metadata.yaml`` (version 9) for one MCAP file in ``bag_dir``."""
    total = sum(count for _, count, _ in topics.values())
    info = {
        "version": 9,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": max(0, last - first)},
        "starting_time": {"nanoseconds_since_epoch": first},
        "message_count": total,
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": topic,
                    "type": datatype,
                    "serialization_format": "cdr",
                    "offered_qos_profiles": qos,
                    "type_description_hash": "",
                },
                "message_count": count,
            }
            for topic, (datatype, count, qos) in sorted(topics.items())
        ],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [filename],
        "files": [{
            "path": filename,
            "starting_time": {"nanoseconds_since_epoch": first},
            "duration": {"nanoseconds": max(0, last - first)},
            "message_count": total,
        }],
        "custom_data": {},
        "ros_distro": "jazzy",
    }
    (bag_dir / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}, sort_keys=False))


def is_complete(path: str | Path) -> bool:
    """True if the MCAP file has its footer and summary (it was finalized)."""
    try:
        with open(path, "rb") as f:
            return make_reader(f).get_summary() is not None
    except Exception:  # a truncated file makes the seeking reader fail in several ways
        return False


def recover(path: str | Path, out: str | Path) -> int:
    """Copy every whole record of a possibly truncated MCAP file into a complete one at ``out``.

    Returns the number of messages recovered; what a killed writer had not yet written (its
    open chunk) is lost, nothing else. Also writes ``metadata.yaml`` beside ``out``.
    """
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    new_ids: dict[tuple[str, int], int] = {}  # ("schema"|"channel", old id) -> id in the new file
    counts: dict[int, int] = {}
    first = last = None
    with open(path, "rb") as src, open(out, "wb") as dst:
        writer = RawWriter(dst)
        writer.start(profile="ros2", library="biped_gait recover")
        try:
            for record in StreamReader(src, skip_magic=False, emit_chunks=False).records:
                if isinstance(record, Schema) and record.id not in schemas:
                    schemas[record.id] = record
                    new_ids["schema", record.id] = writer.register_schema(record.name, record.encoding, record.data)
                elif isinstance(record, Channel) and record.id not in channels and ("schema", record.schema_id) in new_ids:
                    channels[record.id] = record
                    new_ids["channel", record.id] = writer.register_channel(
                        record.topic, record.message_encoding, new_ids["schema", record.schema_id], record.metadata
                    )
                elif isinstance(record, Message) and record.channel_id in channels:
                    writer.add_message(
                        new_ids["channel", record.channel_id], record.log_time, record.data, record.publish_time, record.sequence
                    )
                    counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
                    first = record.log_time if first is None else min(first, record.log_time)
                    last = record.log_time if last is None else max(last, record.log_time)
        except Exception:  # the truncated tail: everything before it was copied
            pass
        writer.finish()
    topics = {
        ch.topic: (schemas[ch.schema_id].name if ch.schema_id in schemas else "", counts.get(cid, 0), [])
        for cid, ch in channels.items()
    }
    write_metadata(Path(out).parent, Path(out).name, first or 0, last or 0, topics)
    return sum(counts.values())
