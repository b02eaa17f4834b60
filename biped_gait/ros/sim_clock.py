"""The simulated time on ``/clock`` (rosgraph_msgs/Clock), as Gazebo publishes it: nodes with
``use_sim_time`` follow it. Published before each sample's messages, with the sample's stamp
(ns); not recorded (the recording's log times are that time, and replay ``--clock``
publishes it again from them)."""

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

    def encode(self, stamps_ns: np.ndarray) -> np.ndarray:
        """The serialized Clock messages of ``stamps_ns`` (ns), one row each."""
        return self._template.encode(np.zeros((len(stamps_ns), 0)), stamp_ints(stamps_ns))
