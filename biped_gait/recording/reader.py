"""Reading a recording: a rosbag2 directory (``metadata.yaml`` and one MCAP file) or a bare
``.mcap`` file, with the MCAP readers (no ROS code). Messages come raw (CDR bytes) or decoded
from the schemas inside the file (``mcap_ros2``), never by importing code the file names.

Times are ns since the epoch in the file, s from the first message where decoded.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap.records import Channel, Message
from mcap.summary import Summary
from mcap.writer import MCAP0_MAGIC
from mcap_ros2.decoder import DecoderFactory

from ..core.model.yaml_files import load_yaml_file, parse_yaml
from .metadata import METADATA_NAME

MAX_METADATA_BYTES = 16 * 1024 * 1024  # a metadata.yaml is a few kB per topic


class BagError(ValueError):
    """A recording that cannot be read; the message is one line."""


@dataclass(frozen=True)
class Bag:
    """A finalized MCAP recording: the file, its rosbag2 metadata (empty without metadata.yaml)
    and its MCAP summary (channels, schemas, statistics; times in ns)."""

    path: Path
    directory: Path
    metadata: dict
    summary: Summary

    @property
    def start_ns(self) -> int:
        """Log time of the first message (ns)."""
        return self.summary.statistics.message_start_time

    @property
    def duration(self) -> float:
        """From the first to the last message's log time (s)."""
        return (self.summary.statistics.message_end_time - self.start_ns) * 1e-9

    def topics(self) -> dict[str, tuple[str, int]]:
        """Topic -> (type 'pkg/msg/Type', message count), in the order of the channels."""
        counts = self.summary.statistics.channel_message_counts
        topics: dict[str, tuple[str, int]] = {}
        for cid, channel in self.summary.channels.items():
            schema = self.summary.schemas.get(channel.schema_id)
            _, before = topics.get(channel.topic, ("", 0))
            topics[channel.topic] = (schema.name if schema else "", before + counts.get(cid, 0))
        return topics

    def offered_qos(self, topic: str) -> list[dict]:
        """The QoS profiles the recorded publishers of ``topic`` offered (rosbag2 keys:
        history, depth, reliability, durability, ...): from metadata.yaml, else from the MCAP
        channel's metadata (where rosbag2's MCAP plugin keeps them); empty when not recorded."""
        for entry in self.metadata.get("topics_with_message_count", []):
            meta = entry.get("topic_metadata", {})
            if meta.get("name") == topic:
                return _profiles(meta.get("offered_qos_profiles"))
        channel = next((c for c in self.summary.channels.values() if c.topic == topic), None)
        return _profiles(channel.metadata.get("offered_qos_profiles") if channel else None)

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[tuple[Channel, Message]]:
        """The raw records (``Message.data``: CDR bytes) of ``topics`` (all: None) in log-time order."""
        for _, channel, message, _ in self._read(topics, decode=False):
            yield channel, message

    def decoded(self, topics: Iterable[str] | None = None) -> Iterator[tuple[str, float, Any]]:
        """(topic, time in s from the first message, decoded message) in log-time order."""
        for _, channel, message, decoded in self._read(topics, decode=True):
            yield channel.topic, (message.log_time - self.start_ns) * 1e-9, decoded

    def _read(self, topics: Iterable[str] | None, decode: bool) -> Iterator[tuple]:
        try:
            with open(self.path, "rb") as stream:
                reader = make_reader(stream, decoder_factories=[DecoderFactory()])
                topics = None if topics is None else list(topics)
                if decode:
                    yield from reader.iter_decoded_messages(topics=topics, log_time_order=True)
                else:
                    for schema, channel, message in reader.iter_messages(topics=topics, log_time_order=True):
                        yield schema, channel, message, None
        except OSError as exc:
            raise BagError(f"{self.path}: {exc.strerror}") from None
        except Exception as exc:  # noqa: BLE001  a damaged file fails in the reader in many ways
            raise BagError(f"{self.path}: unreadable MCAP data ({type(exc).__name__}: {_one_line(exc)})") from None


def _profiles(value) -> list[dict]:
    """rosbag2 writes the offered profiles as a YAML list, older versions as YAML text."""
    if isinstance(value, str):
        value = parse_yaml(value, "offered_qos_profiles")
    return list(value or [])


def _one_line(exc: Exception) -> str:
    return " ".join(str(exc).split()) or "no details"


def open_bag(path: str | Path) -> Bag:
    """The recording at ``path``: a rosbag2 directory or a bare ``.mcap`` file (its metadata
    then comes from a metadata.yaml beside it that names it). ``BagError`` if it is missing,
    is not MCAP, or was not finalized (no summary)."""
    path = Path(path)
    if path.is_dir():
        metadata = _metadata(path)
        files = metadata.get("relative_file_paths") or sorted(p.name for p in path.glob("*.mcap"))
        if not files:
            raise BagError(f"{path}: no .mcap file in this directory")
        if len(files) > 1:
            raise BagError(f"{path}: {len(files)} MCAP files; only single-file recordings are read")
        mcap_path, directory = path / files[0], path
    elif path.is_file():
        mcap_path, directory = path, path.parent
        metadata = _metadata(directory)
        if path.name not in metadata.get("relative_file_paths", []):
            metadata = {}
    else:
        raise BagError(f"{path}: no such file or directory")
    try:
        with open(mcap_path, "rb") as stream:
            magic = stream.read(len(MCAP0_MAGIC))
            summary = _summary(stream) if magic == MCAP0_MAGIC else None
    except OSError as exc:
        raise BagError(f"{mcap_path}: {exc.strerror}") from None
    if magic != MCAP0_MAGIC:
        raise BagError(f"{mcap_path}: not an MCAP file")
    if summary is None or summary.statistics is None:
        raise BagError(f"{mcap_path}: the recording was not finalized (no MCAP summary); "
                       "'biped-gait recover' rebuilds it")
    return Bag(mcap_path, directory, metadata, summary)


def _summary(stream) -> Summary | None:
    """The MCAP summary of ``stream``; None if it has none."""
    try:
        stream.seek(0)
        return make_reader(stream).get_summary()
    except Exception:  # noqa: BLE001  a truncated file makes the seeking reader fail in several ways
        return None


def _metadata(directory: Path) -> dict:
    """rosbag2_bagfile_information of ``directory/metadata.yaml``; {} if there is none."""
    path = directory / METADATA_NAME
    if not path.is_file():
        return {}
    try:
        info = load_yaml_file(path, "metadata file", MAX_METADATA_BYTES)["rosbag2_bagfile_information"]
    except (ValueError, TypeError, KeyError):
        raise BagError(f"{path}: not a rosbag2 metadata file") from None
    return info if isinstance(info, dict) else {}


