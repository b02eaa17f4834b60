"""Publishers whose messages are also recorded (and shown live, when a live view runs): each
message is serialized once, and the same CDR bytes go to the publisher, to the recorder (with
the topic's QoS and type hash in the recording, as rosbag2 writes them) and to the live view.
A recorded-only message is serialized on the recorder's writer thread, off the caller's path.
The recorder and the live view can change at run time (``record_to``, ``show_on``): a latched
topic's last message goes to the new one at once, as a late subscriber would get it."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING

from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import DurabilityPolicy, QoSProfile

from ..recording.background import BackgroundRecorder
from ..recording.writer import RecordingError
from ..recording.schemas import type_name
from .cdr import serialized
from .qos import describe

if TYPE_CHECKING:  # the live view's SDK is loaded only where a live view runs
    from .live_view import LiveView


@contextmanager
def raw_sender(publisher: Publisher) -> Iterator[Callable[[bytes], None]]:
    """``publisher``'s publish of serialized bytes for many messages in a row (a step's samples),
    its handle held once for all of them: rclpy's ``publish`` takes it for each message, which is
    half of its cost."""
    with publisher.handle:
        yield publisher.handle.publish_raw


class RecordedPublisher:
    """A publisher of ``msg_type`` on ``topic`` (``publish=False``: recorded only) whose
    messages ``recorder`` (if any) records and ``live`` (if any) shows."""

    def __init__(self, node: Node, msg_type: type, topic: str, qos: QoSProfile, recorder: BackgroundRecorder | None,
                 publish: bool = True, live: "LiveView | None" = None) -> None:
        self.publisher = node.create_publisher(msg_type, topic, qos) if publish else None
        self.topic = self.publisher.topic_name if publish else node.resolve_topic_name(topic)
        self.datatype = type_name(msg_type)
        self.qos = qos
        self.latched = qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
        self.last: tuple[bytes, int | None] | None = None  # a latched topic's last message and stamp (ns)
        self.recorder: BackgroundRecorder | None = None
        self.live: "LiveView | None" = None
        self.record_to(recorder)
        self.show_on(live)

    def record_to(self, recorder: BackgroundRecorder | None) -> None:
        """Record to ``recorder`` from now on (None: no longer record)."""
        if recorder is not None:
            recorder.add_topic(self.topic, self.datatype, describe(self.qos))
            if self.last is not None:
                recorder.write(self.topic, *self.last)
        self.recorder = recorder

    def show_on(self, live: "LiveView | None") -> None:
        """Show on ``live`` from now on (None: no longer show)."""
        if live is not None:
            live.add_topic(self.topic, self.datatype, latched=self.latched)
            if self.last is not None:
                live.log(self.topic, *self.last)
        self.live = live

    def publish(self, msg, stamp_ns: int | None = None) -> None:
        """Publish ``msg`` and record it at ``stamp_ns`` (ns; default: now)."""
        if self.publisher is None and self.live is None:
            self.record_later(lambda: msg, stamp_ns)
            return
        data = serialized(msg)
        if self.latched:
            self.last = (data, stamp_ns)
        self.send(data, stamp_ns)
        recorder = self.recorder
        if recorder is not None:
            recorder.write(self.topic, data, stamp_ns)

    def record_later(self, make: Callable[[], object], stamp_ns: int | None = None) -> None:
        """Record the message ``make()`` returns, built and serialized on the recorder's writer
        thread (for a recorded-only topic), at ``stamp_ns`` (ns; default: now)."""
        recorder = self.recorder
        if recorder is not None:
            recorder.write(self.topic, lambda: serialized(make()), stamp_ns)

    def send(self, data: bytes, stamp_ns: int | None = None) -> None:
        """Publish and show the CDR bytes ``data`` without recording them: the caller records
        them with others at once (``BackgroundRecorder.write_samples``)."""
        if self.publisher is not None:
            self.publisher.publish(data)
        live = self.live
        if live is not None:
            live.log(self.topic, data, stamp_ns)

    @contextmanager
    def sending(self) -> Iterator[Callable[[bytes, int], None]]:
        """``send`` for many messages in a row (a step's samples), the publisher's handle held
        once for all of them (``raw_sender``)."""
        if self.publisher is None:
            yield self.send
            return
        with raw_sender(self.publisher) as publish:
            if self.live is None:
                yield lambda data, _stamp_ns: publish(data)
            else:
                live, topic = self.live, self.topic

                def send(data: bytes, stamp_ns: int) -> None:
                    publish(data)
                    live.log(topic, data, stamp_ns)

                yield send

    def subscription_count(self) -> int:
        """Subscribers matched to the live publisher (0 if recorded only)."""
        return self.publisher.get_subscription_count() if self.publisher is not None else 0


def finish_recording(publishers: Sequence[RecordedPublisher], recorder: BackgroundRecorder, logger) -> None:
    """Stop ``publishers`` recording to ``recorder`` and finish its file (what is queued is
    written): a run-time ``record: false``; a failure is one error line of ``logger``."""
    for publisher in publishers:
        publisher.record_to(None)
    try:
        recorder.close()
    except RecordingError as exc:
        logger.error(str(exc))
    else:
        logger.info(f"recording finalized: {recorder.path}")
