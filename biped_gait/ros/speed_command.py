"""The simulator's speed command: ``/cmd_vel`` (geometry_msgs/Twist in ``base_link``, REP 103:
linear.x in m/s, angular.z in rad/s, positive turning left, as ROS walking engines take it)
walked by the core's speed follower with transition steps (docs/model.md section 8.8). No
physics here.

The follower is made when the walk starts, for its gait (``transitions.follower_for``: the rule
``least_effort`` needs the current gait atlas, else the walker keeps a fixed cadence, with a
warning). A command is walked as the gait of speed linear.x on the circle of radius
linear.x / angular.z (a model with hip roll and yaw joints; the others walk straight and ignore
angular.z, with a warning once), clamped to the envelope (a warning stating it when the clamped
command changes), which is published on ``~/velocity_envelope`` (transient local) when the walk
starts. linear.y (no sideways gaits), linear.z, angular.x and angular.y are ignored (a warning
once).

linear.x below ``STOP_SPEED`` (0 included) asks the walk to stop: the core plans the stop step
from the walked gait (``start_stop.plan_stop``, in a thread of its own, once per gait) and says
why it cannot be made (for the shipped parameter sets it cannot: docs/model.md section 8.10);
the command is then walked as the slowest gait of the envelope, as before.
"""

from __future__ import annotations

import math
import threading

from biped_gait_interfaces.msg import VelocityEnvelope
from geometry_msgs.msg import Twist
from rclpy.node import Node
from std_msgs.msg import Header

from ..core.dynamics.hybrid import HybridStep
from ..core.dynamics.settings import DEFAULTS
from ..core.model.biped import BipedModel
from ..core.walking.start_stop import why_not
from ..core.walking.world import BASE_FRAME
from ..core.walking.transitions import Envelope, SpeedFollower, follower_for
from ..core.walking.runner import Walker
from ..recording import topics
from .qos import LATCHED
from .walk_messages import stamp_msg

STOP_SPEED = 1e-3  # m/s: a commanded linear.x below this asks the walk to stop


class SpeedCommand:
    """/cmd_vel for ``node``'s walk: speed rule ``rule``, at most ``max_change`` (m/s) and
    ``max_curvature_change`` (1/m) of change of the aimed gait's speed and curvature per step,
    curvatures up to ``max_curvature`` (1/m); ``publisher`` makes the envelope's publisher
    (message type, topic, QoS), recorded with the rest."""

    def __init__(self, node: Node, rule: str, max_change: float, max_curvature: float, max_curvature_change: float,
                 publisher) -> None:
        self.node, self.rule, self.max_change = node, rule, max_change
        self.max_curvature, self.max_curvature_change = max_curvature, max_curvature_change
        self.follower: SpeedFollower | None = None
        self._pending: tuple[float, float] | None = None  # a command that came before the walk started
        self._lock = threading.Lock()
        self._said_clamped: tuple[float, float] | None = None
        self._said_ignored: set[str] = set()
        self._stop_checked: set[tuple[float, float]] = set()  # the gaits (L, T) a stop was planned from
        self._grid = DEFAULTS.walk_steps
        self.pub_envelope = publisher(VelocityEnvelope, topics.VELOCITY_ENVELOPE, LATCHED)

    def start(self, walker: Walker, source: str | None, stamp_ns: int) -> None:
        """Make the follower of ``walker``'s gait (``source``: its parameter set as given), and
        publish its envelope stamped ``stamp_ns`` (ns: the walk's start in simulated time)."""
        follower, note = follower_for(walker, DEFAULTS, self.rule, self.max_change, source, self.max_curvature,
                                      self.max_curvature_change)
        if note:
            self.node.get_logger().warn(f"speed command: {note}")
        self.node.get_logger().info(f"speed command: {follower.rule.describe()}; envelope {follower.envelope.describe()}")
        self.pub_envelope.publish(envelope_msg(follower.envelope, follower.rule.describe(), stamp_msg(stamp_ns)),
                                  stamp_ns)
        with self._lock:
            self.follower, pending = follower, self._pending
            self._grid = walker.grid
        if pending is not None:
            self._command(*pending)

    def on_twist(self, msg: Twist) -> None:
        """A /cmd_vel message: linear.x the commanded speed (m/s), angular.z the yaw rate (rad/s)."""
        ignored = [name for name, value in (("linear.y", msg.linear.y), ("linear.z", msg.linear.z),
                                            ("angular.x", msg.angular.x), ("angular.y", msg.angular.y))
                   if abs(value) > 1e-9 and name not in self._said_ignored]
        if ignored:
            self._said_ignored.update(ignored)
            why = " (the gaits have no sideways step)" if "linear.y" in ignored else ""
            self.node.get_logger().warn(f"speed command: {', '.join(ignored)} ignored{why}")
        if not (math.isfinite(msg.linear.x) and math.isfinite(msg.angular.z)):
            self.node.get_logger().warn(f"speed command: linear.x and angular.z must be finite, got "
                                        f"{msg.linear.x}, {msg.angular.z}: ignored")
            return
        with self._lock:
            if self.follower is None:
                self._pending = (msg.linear.x, msg.angular.z)
                return
        self._command(msg.linear.x, msg.angular.z)

    def _command(self, speed: float, yaw_rate: float) -> None:
        follower = self.follower
        if speed < STOP_SPEED:
            self._stop(follower)
        if yaw_rate and follower.envelope.max_curvature == 0.0 and "angular.z" not in self._said_ignored:
            self._said_ignored.add("angular.z")
            self.node.get_logger().warn("speed command: angular.z ignored: the model walks straight (turning needs "
                                        "hip roll and yaw joints, e.g. params aoustin2013-hips)")
            yaw_rate = 0.0
        walked, turned, clamped = follower.command(speed, yaw_rate)
        if clamped and (walked, turned) != self._said_clamped:
            self.node.get_logger().warn(
                f"speed command {speed:g} m/s, {yaw_rate:g} rad/s is outside the envelope "
                f"({follower.envelope.describe()}): clamped to {walked:.3f} m/s, {turned:.3f} rad/s")
        self._said_clamped = (walked, turned) if clamped else None

    def _stop(self, follower: SpeedFollower) -> None:
        """A command to stop: plan the stop from the gait aimed at (once per gait, in a thread:
        it takes a second or two) and log the outcome."""
        orbit = follower.orbit
        key = (orbit.step_length, orbit.period)
        if key in self._stop_checked:
            return
        self._stop_checked.add(key)
        logger, grid = self.node.get_logger(), self._grid

        def plan() -> None:
            hybrid = HybridStep(BipedModel.from_params(follower.bm.params))
            reason = why_not("stop", hybrid, orbit, grid)
            logger.warn(f"speed command: cannot stop from the gait L = {orbit.step_length:.3f} m, T = "
                        f"{orbit.period:.3f} s: {reason}; walking on at the slowest gait")

        threading.Thread(target=plan, name="stop-plan", daemon=True).start()

    def before_step(self, walker: Walker) -> None:
        """One transition towards the commanded speed and turn, if the walker is not at them
        (walker thread)."""
        if self.follower is None:
            return
        transition = self.follower.before_step(walker)
        if transition is not None and transition.failure:
            self.node.get_logger().warn(f"speed command: no transition before step {transition.step}: "
                                        f"{transition.failure}")


def envelope_msg(envelope: Envelope, rule: str, stamp) -> VelocityEnvelope:
    """The VelocityEnvelope message of ``envelope`` (speed rule described by ``rule``)."""
    return VelocityEnvelope(
        header=Header(stamp=stamp, frame_id=BASE_FRAME), min_linear_x=envelope.low, max_linear_x=envelope.high,
        max_curvature=envelope.max_curvature, max_angular_z=envelope.max_curvature * envelope.high,
        max_linear_x_change=envelope.max_change, max_curvature_change=envelope.max_curvature_change,
        follows_linear_y=False, speed_rule=rule, description=envelope.describe())
