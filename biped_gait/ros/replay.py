"""Replay of a recording (entry point ``biped-gait-replay``), like ``ros2 bag play``:
``biped-gait-replay BAG [--rate R] [--loop] [--clock [HZ]] [--topics T1 T2 ...] [--start-paused]``.

BAG is a rosbag2 directory or a bare ``.mcap`` file. Each message is published on its topic,
as the CDR bytes recorded, at ``start + (log time - first log time) / R`` on the monotonic
clock, ``start`` being when playback begins: at once, or with ``--start-paused`` when the
service ``~/resume`` (std_srvs/Trigger) is called, e.g. once subscribers see the publishers
(DDS discovery between processes takes from milliseconds to seconds). ``--clock`` publishes
the playback time on ``/clock`` (rosgraph_msgs/Clock, HZ times per wall second, 40 by default
as ``ros2 bag play``): the recording's log times, from its first message's, advancing at R
(while paused: the first message's time), so that nodes with ``use_sim_time`` follow the
recording. ``--loop`` plays the recording again and again, each time later by the recording's
span (its duration and its shortest interval between messages), and restamps it forward: every
``builtin_interfaces/Time`` in a message (header stamps, the transforms' stamps) that is not
zero is moved by as much, so that time never goes back for a subscriber (the first pass
publishes the recorded bytes as they are). Publishers have the
message class of the recorded type and the QoS the recording's publishers offered
(metadata.yaml; transient-local for ``/robot_description``). Topics whose type has no Python
code here are skipped with one warning line; types are looked up only among the project's and
the standard ROS 2 message packages (``TRUSTED_PACKAGES``): a file never makes the replay import
a module it names (decoding for analysis uses the schema text in the file).

Exit status: 0 at the end of the recording (``--loop``: replays until stopped) or on SIGINT /
SIGTERM; 2 with one line on stderr for a missing or unreadable recording, unknown
``--topics``, a bad rate or nothing publishable; 1 if reading fails during playback.
"""

from __future__ import annotations

import importlib
import math
import re
import sys
import threading
import time
from pathlib import Path

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

from builtin_interfaces.msg import Time as TimeMsg
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.utilities import remove_ros_args
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Trigger

from ..recording import topics
from ..recording.reader import Bag, BagError, open_bag
from ..arguments import OneLineParser
from .cdr import serialized
from .process import run_node
from .qos import CLOCK

PROGRAM = "biped-gait-replay"
NODE_NAME = "biped_gait_replay"
DEFAULT_DEPTH = 100  # keep-last depth of topics recorded without QoS profiles
CLOCK_RATE = 40.0  # Hz of wall time: /clock messages of --clock without a rate (as ros2 bag play)


# The packages whose message classes a replay may use: the project's own interfaces and the
# standard ROS 2 message packages. A recording names its types in its schemas; no other module is
# ever imported because a file names it.
TRUSTED_PACKAGES = frozenset({
    "biped_gait_interfaces", "tf2_msgs", "std_msgs", "builtin_interfaces", "geometry_msgs", "sensor_msgs",
    "nav_msgs", "trajectory_msgs", "action_msgs", "rcl_interfaces", "diagnostic_msgs", "visualization_msgs",
    "shape_msgs", "statistics_msgs", "rosgraph_msgs", "unique_identifier_msgs", "type_description_interfaces",
})
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9]*$")


def message_class(datatype: str) -> type | None:
    """The rclpy message class of 'pkg/msg/Type' (or 'pkg/Type') for a package of
    ``TRUSTED_PACKAGES``; None for any other name, or a type not installed here."""
    parts = datatype.split("/")
    if len(parts) not in (2, 3) or (len(parts) == 3 and parts[1] != "msg"):
        return None
    package, name = parts[0], parts[-1]
    if package not in TRUSTED_PACKAGES or not _NAME.match(name):
        return None
    try:
        cls = getattr(importlib.import_module(f"{package}.msg"), name)
    except (ImportError, AttributeError):
        return None
    is_message = isinstance(cls, type) and hasattr(type(cls), "__import_type_support__")
    return cls if is_message and cls.__module__.startswith(f"{package}.msg") else None


def _policy(enum: type, value: str | int | None):
    """A QoS policy as rosbag2 writes it: its short name ('reliable') or its number."""
    if value is None:
        return enum.SYSTEM_DEFAULT
    return enum[value.upper()] if isinstance(value, str) else enum(value)


def replay_qos(offered: list[dict]) -> QoSProfile:
    """The QoS to replay a topic with, adapted from what its recorded publishers offered (as
    ``ros2 bag play`` does): reliable, transient-local only if all of them were; keep-all if
    one was, else keep-last with the largest depth. None recorded: reliable, volatile,
    keep-last ``DEFAULT_DEPTH``."""
    if not offered:
        return QoSProfile(depth=DEFAULT_DEPTH)

    def every(enum: type, key: str, value) -> bool:
        return all(_policy(enum, profile.get(key)) == value for profile in offered)

    keep_all = any(_policy(HistoryPolicy, profile.get("history")) == HistoryPolicy.KEEP_ALL for profile in offered)
    reliable = every(ReliabilityPolicy, "reliability", ReliabilityPolicy.RELIABLE)
    latched = every(DurabilityPolicy, "durability", DurabilityPolicy.TRANSIENT_LOCAL)
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL if keep_all else HistoryPolicy.KEEP_LAST,
        depth=max(int(p.get("depth") or 0) for p in offered) or DEFAULT_DEPTH,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )


def select_topics(bag: Bag, wanted: list[str] | None) -> tuple[dict[str, tuple[type, QoSProfile]], list[str]]:
    """Publishable topics of ``wanted`` (all: None) -> (message class, QoS), and the skipped
    ones as 'topic (type)'. ``BagError`` for a topic not in the recording or none publishable."""
    known = bag.topics()
    wanted = list(known) if not wanted else list(dict.fromkeys(wanted))
    unknown = [topic for topic in wanted if topic not in known]
    if unknown:
        raise BagError(f"unknown topics {', '.join(unknown)}: the recording has {', '.join(known)}")
    outputs, skipped = {}, []
    for topic in wanted:
        datatype = known[topic][0]
        cls = message_class(datatype)
        if cls is None:
            skipped.append(f"{topic} ({datatype})")
            continue
        try:
            outputs[topic] = (cls, replay_qos(bag.offered_qos(topic)))
        except (KeyError, ValueError, TypeError, AttributeError):
            raise BagError(f"{topic}: unreadable QoS profiles in the recording's metadata") from None
    if not outputs:
        raise BagError(f"nothing to replay: no Python code here for the types of {', '.join(skipped)}")
    return outputs, skipped


def shift_times(msg, offset_ns: int) -> None:
    """Move every non-zero ``builtin_interfaces/Time`` inside ``msg`` (nested messages and
    sequences of them included) ``offset_ns`` (ns) later, in place."""
    for name in msg.get_fields_and_field_types():
        value = getattr(msg, name)
        items = value if isinstance(value, list) else [value]
        for item in items:
            if isinstance(item, TimeMsg):
                if item.sec or item.nanosec:
                    total = item.sec * 1_000_000_000 + item.nanosec + offset_ns
                    item.sec, item.nanosec = total // 1_000_000_000, total % 1_000_000_000
            elif hasattr(type(item), "get_fields_and_field_types"):
                shift_times(item, offset_ns)


def restamped(data: bytes, cls: type, offset_ns: int) -> bytes:
    """The CDR bytes ``data`` of a ``cls`` message with its times ``offset_ns`` (ns) later."""
    if not offset_ns:
        return data
    msg = deserialize_message(data, cls)
    shift_times(msg, offset_ns)
    return serialized(msg)


class ReplayNode(Node):
    """Publishes the recorded messages of the selected topics at their recorded times / rate
    from a worker thread, started by the first spin; ends the process's spin at the end."""

    def __init__(self, bag: Bag, outputs: dict[str, tuple[type, QoSProfile]], skipped: list[str],
                 rate: float, loop: bool, paused: bool, clock_rate: float | None = None) -> None:
        super().__init__(NODE_NAME)
        self.bag, self.rate, self.loop = bag, rate, loop
        self.outputs = {topic: self.create_publisher(cls, topic, qos) for topic, (cls, qos) in outputs.items()}
        self.classes = {topic: cls for topic, (cls, _) in outputs.items()}
        self._began: float | None = None  # monotonic time (s) of the first message's playback
        self._span = 0  # ns between a pass's first message and the next pass's
        if clock_rate:
            self._clock_publisher = self.create_publisher(Clock, topics.CLOCK, CLOCK)
            self.create_timer(1.0 / clock_rate, self._publish_clock)
        if skipped:
            self.get_logger().warning(f"not replayed (message type not available here): {', '.join(skipped)}")
        self.failed = False
        self.exit_requested = threading.Event()
        self.published = 0
        self._stop = threading.Event()
        self._resumed = threading.Event()
        if not paused:
            self._resumed.set()
        self.create_service(Trigger, "~/resume", self._on_resume)
        count = sum(n for topic, (_, n) in bag.topics().items() if topic in self.outputs)
        self.get_logger().info(f"replaying {count} messages on {len(self.outputs)} topics from {bag.path} "
                               f"at rate {rate:g}{', looping' if loop else ''}{', paused' if paused else ''}"
                               f"{f', /clock at {clock_rate:g} Hz' if clock_rate else ''}")
        self._worker = threading.Thread(target=self._run, name="replay", daemon=True)
        self._starter = self.create_timer(0.0, self._start)

    def _start(self) -> None:
        """Once, when the executor spins: begin (so that the end of the recording ends the spin)."""
        self.destroy_timer(self._starter)
        self._worker.start()

    def _on_resume(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        """``~/resume``: begin a replay started paused."""
        response.success = not self._resumed.is_set()
        response.message = "resumed" if response.success else "not paused"
        self._resumed.set()
        return response

    def playback_ns(self) -> int:
        """The recording's time now playing (ns): its first message's until playback begins."""
        if self._began is None:
            return self.bag.start_ns
        return self.bag.start_ns + round((time.monotonic() - self._began) * self.rate * 1e9)

    def _publish_clock(self) -> None:
        now = self.playback_ns()
        self._clock_publisher.publish(Clock(clock=TimeMsg(sec=now // 1_000_000_000, nanosec=now % 1_000_000_000)))

    def _run(self) -> None:
        try:
            self._resumed.wait()
            passes = 0
            while not self._stop.is_set() and self._play(passes) and self.loop:
                passes += 1
            if self._stop.is_set():
                return
            self.get_logger().info(f"end of the recording: {self.published} messages published")
        except Exception as exc:  # noqa: BLE001  reported; a signal's shutdown is not a failure
            if not self._stop.is_set() and self.context.ok():
                self.failed = True
                self.get_logger().error(f"replay failed: {exc}")
        finally:
            self.exit_requested.set()  # end the spin: the process exits

    def _play(self, index: int) -> bool:
        """Publish the recording once, its ``index``-th pass (0: the first), each message when
        it is due: the start (monotonic clock, s; when the first message of the first pass has
        been read) plus its log time's offset from the recording's first message, plus
        ``index`` spans, over the rate; restamped by ``index`` spans. False if stopped."""
        offset = index * self._span
        last, gap = None, 0
        for channel, message in self.bag.messages(list(self.outputs)):
            if self._began is None:
                self._began = time.monotonic()
            due = self._began + (message.log_time - self.bag.start_ns + offset) * 1e-9 / self.rate
            if self._stop.wait(max(0.0, due - time.monotonic())):
                return False
            topic = channel.topic
            self.outputs[topic].publish(restamped(message.data, self.classes[topic], offset))
            self.published += 1
            if last is not None and message.log_time > last:
                gap = min(gap, message.log_time - last) if gap else message.log_time - last
            last = message.log_time
        if index == 0 and last is not None:
            self._span = last - self.bag.start_ns + (gap or 1)
        return True

    @property
    def exit_status(self) -> int:
        """1 if reading failed during playback, else 0."""
        return 1 if self.failed else 0

    def close(self) -> None:
        """Stop publishing (end of the recording, SIGINT, SIGTERM)."""
        self._stop.set()
        self._resumed.set()
        if self._worker.is_alive():
            self._worker.join(timeout=5.0)


def build_parser() -> OneLineParser:
    parser = OneLineParser(prog=PROGRAM, description="Publish a recording's messages with their recorded timing.")
    parser.add_argument("bag", type=Path, metavar="BAG", help="rosbag2 directory or .mcap file")
    parser.add_argument("--rate", type=float, default=1.0, metavar="R",
                        help="speed factor: log-time differences are divided by it")
    parser.add_argument("--loop", action="store_true", help="replay again and again until stopped, each pass "
                        "restamped later by the recording's span")
    parser.add_argument("--clock", type=float, nargs="?", const=CLOCK_RATE, metavar="HZ",
                        help=f"publish the playback time on /clock, HZ times per second (default {CLOCK_RATE:g})")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC", help="replay only these topics")
    parser.add_argument("--start-paused", action="store_true", help="wait for a call of the ~/resume service")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point ``biped-gait-replay``; returns the exit status. ROS arguments
    (``--ros-args ...``) go to rclpy, the others to this command."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser()
    args = parser.parse_args(remove_ros_args([PROGRAM, *argv])[1:])
    if not (math.isfinite(args.rate) and args.rate > 0):
        parser.error(f"--rate must be a positive number, got {args.rate:g}")
    if args.clock is not None and not (math.isfinite(args.clock) and args.clock > 0):
        parser.error(f"--clock must be a positive rate (Hz), got {args.clock:g}")
    try:
        bag = open_bag(args.bag)
        outputs, skipped = select_topics(bag, args.topics)
    except BagError as exc:
        print(f"{PROGRAM}: error: {exc}", file=sys.stderr)
        return 2
    return run_node(lambda: ReplayNode(bag, outputs, skipped, args.rate, args.loop, args.start_paused, args.clock),
                    PROGRAM, threads=2, args=[PROGRAM, *argv])


if __name__ == "__main__":
    sys.exit(main())
