"""Repairing a recording whose writer was killed: every whole record of a truncated MCAP file
copied into a complete one, with rosbag2 metadata (every topic's QoS profiles and type hash
from the channels' metadata, where the recorder keeps them, as rosbag2's MCAP plugin does)."""

from __future__ import annotations

from pathlib import Path

from mcap.reader import make_reader
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import MCAP0_MAGIC, Writer as RawWriter

from ..core.model.yaml_files import parse_yaml
from .metadata import TopicRecord, write_metadata


def is_complete(path: str | Path) -> bool:
    """True if the MCAP file has its footer and summary (it was finalized)."""
    try:
        with open(path, "rb") as f:
            return make_reader(f).get_summary() is not None
    except Exception:  # noqa: BLE001  a truncated file makes the seeking reader fail in several ways
        return False


def _qos(channel: Channel) -> list[dict]:
    """The offered QoS profiles a channel's metadata carries (as the recorder writes them)."""
    try:
        return list(parse_yaml(channel.metadata.get("offered_qos_profiles", ""), "offered_qos_profiles") or [])
    except (ValueError, TypeError):
        return []


def check_mcap(path: str | Path) -> None:
    """``ValueError`` (one line) if ``path`` cannot be read or does not start as an MCAP file."""
    try:
        with open(path, "rb") as src:
            magic = src.read(len(MCAP0_MAGIC))
    except OSError as exc:
        raise ValueError(f"{path}: {exc.strerror or exc}") from None
    if magic != MCAP0_MAGIC:
        raise ValueError(f"{path}: not an MCAP file")


def recover(path: str | Path, out: str | Path) -> int:
    """Copy every whole record of a possibly truncated MCAP file into a complete one at ``out``.

    Returns the number of messages recovered; what a killed writer had not yet written (its
    open chunk) is lost, nothing else. Also writes ``metadata.yaml`` beside ``out``.
    ``ValueError`` (one line) if ``path`` cannot be read or is not an MCAP file.
    """
    check_mcap(path)
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
        except Exception:  # noqa: BLE001  the truncated tail: everything before it was copied
            pass
        writer.finish()
    topics = {
        ch.topic: TopicRecord(schemas[ch.schema_id].name if ch.schema_id in schemas else "", counts.get(cid, 0), _qos(ch),
                              ch.metadata.get("topic_type_hash", ""))
        for cid, ch in channels.items()
    }
    write_metadata(Path(out).parent, Path(out).name, first or 0, last or 0, topics)
    return sum(counts.values())
