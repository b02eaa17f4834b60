"""rosbag2's ``metadata.yaml`` for a recording of one MCAP file."""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path

import yaml

METADATA_NAME = "metadata.yaml"


@dataclass
class TopicRecord:
    """A recorded topic: its type ('pkg/msg/Type'), message count, offered QoS profiles
    (rosbag2 dictionaries) and type description hash ('' when unknown)."""

    type: str
    count: int = 0
    qos: list[dict] = field(default_factory=list)
    type_hash: str = ""


def write_metadata(bag_dir: Path, filename: str, first: int, last: int, topics: dict[str, TopicRecord]) -> None:
    """``bag_dir/metadata.yaml`` (rosbag2 version 9) for the MCAP file ``filename`` whose
    messages span log times ``first`` to ``last`` (ns since the epoch)."""
    total = sum(t.count for t in topics.values())
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
                    "type": record.type,
                    "serialization_format": "cdr",
                    "offered_qos_profiles": copy.deepcopy(record.qos),  # fresh dicts: no YAML aliases
                    "type_description_hash": record.type_hash,
                },
                "message_count": record.count,
            }
            for topic, record in sorted(topics.items())
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
    (bag_dir / METADATA_NAME).write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}, sort_keys=False))
