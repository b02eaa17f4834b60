"""``/diagnostics`` (diagnostic_msgs/DiagnosticArray) of a node, as robots report their health to
tools such as rqt_robot_monitor and Foxglove's diagnostics panels: one ``DiagnosticStatus`` a
part, published every ``PERIOD`` s of wall time from the part's own report (level, message and
key/value figures), and at once when asked (``publish``).

Reports are functions of the node, called on the timer's thread: they read figures the node
keeps under its own locks. Published through the node's recorded publisher, so that a
recording holds the node's health beside what it did (a replay shows it), stamped by the
node's own time (the simulator's: its simulated time).
"""

from __future__ import annotations

import statistics
import threading
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.time import Time
from std_msgs.msg import Header

if TYPE_CHECKING:
    from .recorded import RecordedPublisher

TOPIC = "/diagnostics"
PERIOD = 1.0  # s of wall time between two reports (ROS's diagnostic_updater's default)
QOS = QoSProfile(depth=10)  # reliable, volatile, as diagnostic_updater publishes
OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
RECENT = 100  # solve times kept for the median


@dataclass(frozen=True)
class Report:
    """One part's health: ``level`` (``OK``, ``WARN``, ``ERROR``), a one-line ``message`` and
    its figures by name (units in the names)."""

    level: int
    message: str
    values: Mapping[str, object] = field(default_factory=dict)


class Diagnostics:
    """Publishes (and records) the ``reports`` of ``node`` (part name -> function giving its
    ``Report``) with ``publisher`` (a ``RecordedPublisher`` of ``TOPIC``) every ``PERIOD`` s, in
    ``group`` (default: the node's), stamped ``now_ns()`` (ns; default: the node's clock)."""

    def __init__(self, node: Node, reports: Mapping[str, Callable[[], Report]], publisher: "RecordedPublisher",
                 group: CallbackGroup | None = None, now_ns: Callable[[], int] | None = None):
        self._node = node
        self._reports = dict(reports)
        self._publisher = publisher
        self._now_ns = now_ns or (lambda: node.get_clock().now().nanoseconds)
        self._timer = node.create_timer(PERIOD, self.publish, callback_group=group)

    def statuses(self) -> list[DiagnosticStatus]:
        """Every part's status now."""
        out = []
        for part, report in self._reports.items():
            now = report()
            out.append(DiagnosticStatus(level=now.level, name=f"{self._node.get_name()}: {part}", message=now.message,
                                        hardware_id=self._node.get_fully_qualified_name(),
                                        values=[KeyValue(key=k, value=_text(v)) for k, v in now.values.items()]))
        return out

    def publish(self) -> None:
        """Publish every part's status now."""
        stamp_ns = self._now_ns()
        self._publisher.publish(DiagnosticArray(header=Header(stamp=Time(nanoseconds=stamp_ns).to_msg()), status=self.statuses()),
                                stamp_ns)


def _text(value: object) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


class Counters:
    """Thread-safe counts of the ``names`` (0 until counted) and the recent durations of one
    kind of work (s)."""

    def __init__(self, names: Sequence[str]) -> None:
        self._lock = threading.Lock()
        self._counts: dict[str, int] = dict.fromkeys(names, 0)
        self._times: deque[float] = deque(maxlen=RECENT)
        self._max = 0.0

    def count(self, name: str, n: int = 1) -> None:
        with self._lock:
            self._counts[name] = self._counts.get(name, 0) + n

    def time(self, seconds: float) -> None:
        """One more duration (s)."""
        with self._lock:
            self._times.append(seconds)
            self._max = max(self._max, seconds)

    def figures(self) -> dict[str, object]:
        """The counts, then the last, median (of the last ``RECENT``) and largest durations in ms."""
        with self._lock:
            out: dict[str, object] = dict(self._counts)
            if self._times:
                out.update(last_ms=1000 * self._times[-1], median_ms=1000 * statistics.median(self._times),
                           max_ms=1000 * self._max)
        return out
