"""The simulator's speed command: ``/cmd_vel`` (geometry_msgs/Twist; linear.x in m/s, as ROS
walking engines take it) walked by the core's speed follower with transition steps
(docs/model.md section 8.8). No physics here.

The follower is made when the walk starts, for its gait (``transitions.follower_for``: the rule
``least_effort`` needs the current gait atlas, else the walker keeps a fixed cadence, with a
warning). Each command is clamped to the rule's speeds (a warning when the clamped command
changes); the other twist components are ignored (a warning once): the walk is straight.
"""

from __future__ import annotations

import math
import threading

from geometry_msgs.msg import Twist
from rclpy.node import Node

from ..core.dynamics.settings import DEFAULTS
from ..core.walking.transitions import SpeedFollower, follower_for
from ..core.walking.walk import Walker


class SpeedCommand:
    """/cmd_vel for ``node``'s walk: speed rule ``rule``, at most ``max_change`` (m/s) of change
    of the aimed gait's speed per step."""

    def __init__(self, node: Node, rule: str, max_change: float) -> None:
        self.node, self.rule, self.max_change = node, rule, max_change
        self.follower: SpeedFollower | None = None
        self._pending: float | None = None  # a command that came before the walk started
        self._lock = threading.Lock()
        self._said_clamped: float | None = None
        self._said_ignored = False

    def start(self, walker: Walker, source: str | None) -> None:
        """Make the follower of ``walker``'s gait (``source``: its parameter set as given)."""
        follower, note = follower_for(walker, DEFAULTS, self.rule, self.max_change, source)
        if note:
            self.node.get_logger().warn(f"speed command: {note}")
        self.node.get_logger().info(f"speed command: {follower.rule.describe()}")
        with self._lock:
            self.follower, pending = follower, self._pending
        if pending is not None:
            self._command(pending)

    def on_twist(self, msg: Twist) -> None:
        """A /cmd_vel message: its linear.x is the commanded speed (m/s)."""
        if not self._said_ignored and any(abs(v) > 1e-9 for v in (msg.linear.y, msg.linear.z, msg.angular.x,
                                                                   msg.angular.y, msg.angular.z)):
            self._said_ignored = True
            self.node.get_logger().warn("speed command: only linear.x is followed (the walk is straight); "
                                        "the other components are ignored")
        if not math.isfinite(msg.linear.x):
            self.node.get_logger().warn(f"speed command: a speed must be finite, got {msg.linear.x}: ignored")
            return
        with self._lock:
            if self.follower is None:
                self._pending = msg.linear.x
                return
        self._command(msg.linear.x)

    def _command(self, speed: float) -> None:
        walked, clamped = self.follower.command(speed)
        if clamped and walked != self._said_clamped:
            rule = self.follower.rule
            self.node.get_logger().warn(f"speed command {speed:g} m/s is outside the admissible speeds "
                                        f"[{rule.low:.3f}, {rule.high:.3f}] m/s: clamped to {walked:.3f} m/s")
        self._said_clamped = walked if clamped else None

    def before_step(self, walker: Walker) -> None:
        """One transition towards the commanded speed, if the walker is not at it (walker thread)."""
        if self.follower is None:
            return
        transition = self.follower.before_step(walker)
        if transition is not None and transition.failure:
            self.node.get_logger().warn(f"speed command: no transition before step {transition.step}: "
                                        f"{transition.failure}")
