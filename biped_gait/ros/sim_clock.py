"""The simulated time on ``/clock`` (rosgraph_msgs/Clock), as Gazebo publishes it: nodes with
``use_sim_time`` follow it. Published before each sample's messages, with the sample's stamp
(ns). Not recorded, as ``ros2 bag record`` leaves it out unless asked: each of its values is
the log time of the sample's recorded messages, and replay ``--clock`` (as ``ros2 bag play
--clock``) publishes it again from them; recording it too would give a replay two clocks.

``now_ns`` is the simulator's time now: the stamp of the last sample published, or before the
first the node's clock. Everything the simulator stamps (samples, events, the velocity
envelope, ``/diagnostics``, the step counter) is on this one clock."""

from __future__ import annotations

import numpy as np
from rclpy.node import Node
from rosgraph_msgs.msg import Clock

from ..recording import topics
from .cdr_templates import CdrTemplate
from .qos import CLOCK
from .walk_messages import stamp_ints


def clock_msg(_floats: np.ndarray, ints: np.ndarray) -> Clock:
    """rosgraph_msgs/Clock of a stamp ``ints`` (s, ns)."""
    clock = Clock()
    clock.clock.sec, clock.clock.nanosec = int(ints[0]), int(ints[1])
    return clock


class SimClock:
    """The publisher of ``/clock`` and its messages for many stamps at once."""

    def __init__(self, node: Node) -> None:
        self.publisher = node.create_publisher(Clock, topics.CLOCK, CLOCK)
        self._template = CdrTemplate(clock_msg, 0, 2)
        self._node_clock = node.get_clock()
        self.latest_ns: int | None = None  # the last sample's stamp (ns), set by the walk's thread

    def now_ns(self) -> int:
        """The simulated time now (ns): the last sample's stamp, or the node's clock before it."""
        latest = self.latest_ns
        return latest if latest is not None else self._node_clock.now().nanoseconds

    def encode(self, stamps_ns: np.ndarray) -> np.ndarray:
        """The serialized Clock messages of ``stamps_ns`` (ns), one row each."""
        return self._template.encode(np.zeros((len(stamps_ns), 0)), stamp_ints(stamps_ns))
