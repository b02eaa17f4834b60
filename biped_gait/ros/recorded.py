"""Publishers whose messages are also recorded: each message is serialized once, and the same
CDR bytes go to the publisher and to the MCAP recorder (with the topic's QoS in the recording,
as rosbag2 writes it)."""

from __future__ import annotations

from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.serialization import serialize_message

from ..recording.schemas import type_name
from ..recording.writer import McapRecorder
from .qos import describe


class RecordedPublisher:
    """A publisher of ``msg_type`` on ``topic`` (``publish=False``: recorded only) whose
    messages ``recorder`` (if any) also records."""

    def __init__(self, node: Node, msg_type: type, topic: str, qos: QoSProfile, recorder: McapRecorder | None,
                 publish: bool = True) -> None:
        self.publisher = node.create_publisher(msg_type, topic, qos) if publish else None
        self.topic = self.publisher.topic_name if publish else node.resolve_topic_name(topic)
        self.recorder = recorder
        if recorder is not None:
            recorder.add_topic(self.topic, type_name(msg_type), describe(qos))

    def publish(self, msg, stamp_ns: int | None = None) -> None:
        """Publish ``msg`` and record it at ``stamp_ns`` (ns; default: now)."""
        data = serialize_message(msg)
        if self.publisher is not None:
            self.publisher.publish(data)
        if self.recorder is not None:
            self.recorder.write(self.topic, data, stamp_ns)

    def subscription_count(self) -> int:
        """Subscribers matched to the live publisher (0 if recorded only)."""
        return self.publisher.get_subscription_count() if self.publisher is not None else 0
