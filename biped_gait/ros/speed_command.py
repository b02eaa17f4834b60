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

linear.x below ``STOP_SPEED`` (0 included) asks the walk to stop. **Where a stop is kept** (the
hybrid engine's walk of the default parameter set, started on the gait the package keeps a stop
of, ``core/walking/kept.py``, made ready in a thread at the walk's first command: a walk nobody
steers spends nothing on it): the walk stops at the
touchdown of the next step that aims at that gait and starts within ``kept.SETTLED`` of its start
(``Walker.stop``: the stop's 2 s of double support, then standing, docs/model.md section 14.2; a
walk still settling after a push walks on, said once, its error falling fourfold a step); from
another gait it is first walked back to that gait's speed, then aimed at the gait itself (one
transition step). Then the robot stands, as a walk that began standing: a command to walk
starts it again where a start of that gait is kept (below). **Elsewhere** the command is walked as the slowest gait of
the envelope, and once the walk is there (straight, at its command) the core plans the stop step
from that gait, the one that walks (``start_stop.plan_stop``, in a thread of its own, once per gait
and walk) and says why it cannot be made (for the shipped parameter sets it cannot: docs/model.md
section 8.10).

**The walk's end** (a fall, its steps made: ``end``): commands are no longer walked and nothing
more is said of them, a start or stop still being planned included: the fall's message is the
last. A reset starts a new walk (``start``).

**Standing** (the walk begins standing): no follower and no envelope. **Where a start is kept**
(the hybrid engine's walk of the default parameter set on the gait the package keeps a start of,
made ready in a thread with the stop when the walk begins standing, or during a stop's double
support): a command of at least ``STOP_SPEED``
starts the walk before its next standing phase (``Walker.start``: the start's 2 s of double
support, then I^+ onto the gait, docs/model.md section 14.3), then the follower is made and walks
the command from the gait. **Elsewhere** a command that is not 0 asks for a start onto the walk's
gait, which the core plans (``start_stop.plan_start``, in a thread, once) and refuses with its
physical reason, logged once: the robot stands on.

**Timeout** (as ros2_control's diff_drive_controller ``cmd_vel_timeout``): once a command came,
no /cmd_vel for ``timeout`` s of simulated time counts as a command of 0, taken before the next
step (so within the timeout and a step); logged once per lapse. 0 m/s asks for a stop (above). ``timeout`` 0: never. A paced walk (real-time
factor f > 0) that lags behind the wall clock catches up in a burst of simulated time: the
silence counted is then at most f times the wall time since the command, so that a publisher
that kept its rate is not timed out by the burst.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

from biped_gait_interfaces.msg import VelocityEnvelope
from geometry_msgs.msg import Twist
from rclpy.node import Node
from std_msgs.msg import Header

from ..core.dynamics.hybrid import HybridStep
from ..core.dynamics.settings import DEFAULTS
from ..core.model.biped import BipedModel
from ..core.model.params import BipedParams, load_params
from ..core.walking.orbit import PlannedOrbit
from ..core.walking.start_stop import why_not
from ..core.walking.kept import KeptPlan, Unsettled, kept_plan, kept_why_not
from ..core.walking.phases.standing import Standing
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
    (message type, topic, QoS), recorded with the rest; ``timeout``: s of simulated time without
    a command that count as a command of 0 (0: never), on the clock ``now_ns`` (ns) of a walk
    paced at ``factor`` (0: unpaced; module docstring)."""

    def __init__(self, node: Node, rule: str, max_change: float, max_curvature: float, max_curvature_change: float,
                 publisher, timeout: float, now_ns: Callable[[], int], factor: float) -> None:
        self.node, self.rule, self.max_change = node, rule, max_change
        self.max_curvature, self.max_curvature_change = max_curvature, max_curvature_change
        self.timeout, self._now_ns, self._factor = timeout, now_ns, factor
        self.follower: SpeedFollower | None = None
        self._standing: Walker | None = None  # the walker of a walk that stands: commands are refused
        self._pending: tuple[float, float] | None = None  # a command that came before the walk started
        self._lock = threading.Lock()
        self._last: tuple[int, float] | None = None  # when the last command came: simulated (ns), wall (s) times
        self._lapsed = False  # the timeout has taken the last command as 0
        self._said_clamped: tuple[float, float] | None = None
        self._said_ignored: set[str] = set()
        self._explained: set[tuple[str, float, float]] = set()  # the walk's starts and stops planned: (kind, L, T)
        self._stop_asked = False  # the last command asks the walk to stop
        self._stop: KeptPlan | None = None  # the kept stop of the walk's gait, once made ready (start)
        self._stop_gait: PlannedOrbit | None = None  # the gait it stops from: the walk's first
        self._stop_home = False  # the follower has been sent back to the stop's gait's speed
        self._stop_waits = False  # said that the stop waits for the walk to settle on its gait
        self._preparing: threading.Thread | None = None  # making the kept stop (and start) ready, until joined
        self._unprepared: PlannedOrbit | None = None  # the gait whose kept stop the walk's first command makes ready
        self._start: KeptPlan | None = None  # the kept start onto the standing walk's gait, once made ready
        self._start_asked: tuple[float, float] | None = None  # the command that asks the standing walk to start
        self._start_waits = False  # said that the start waits for the robot to settle
        self._source: str | None = None  # the walk's parameter set as given
        self._startable = False  # the walk stands and a start onto its gait is kept
        self._walk = 0  # which walk this is: a start or stop planned for an earlier one is not said
        self._ended = False  # the walk ended: commands are ignored until the next starts
        self._grid = DEFAULTS.walk_steps
        self.pub_envelope = publisher(VelocityEnvelope, topics.VELOCITY_ENVELOPE, LATCHED)

    @property
    def commanded(self) -> float | None:
        """The speed the walk is commanded (m/s, clamped; the walked gait's before any command),
        None while standing or before the walk."""
        follower = self.follower
        return follower.commanded if follower is not None else None

    def start(self, walker: Walker, source: str | None, stamp_ns: int, standing: bool = False,
              stoppable: bool = False) -> None:
        """Make the follower of ``walker``'s gait (``source``: its parameter set as given), and
        publish its envelope stamped ``stamp_ns`` (ns: the walk's start in simulated time); with
        ``standing``, the walker stands: a command to walk starts it where a start is kept for its
        gait (made ready in a thread), else is refused; ``stoppable``: the walk can take a kept stop
        and start (the hybrid engine's paper walk), made ready in a thread: a standing walk's at once, a
        walking one's stop at its first command (module docstring)."""
        self._last, self._lapsed, self._stop_asked, self._stop_home, self._stop_waits = None, False, False, False, False
        self._start_waits = False
        with self._lock:
            self._walk, self._ended = self._walk + 1, False
            self._explained.clear()
            self._stop, self._stop_gait, self._preparing = None, None, None
            self._start, self._start_asked, self._source = None, None, source
        startable = self._startable = standing and stoppable and not kept_why_not("start", walker.orbit)
        if startable:  # a standing walk that cannot start needs no stop
            self._preparing = self._prepare(walker.orbit, source, ("start", "stop"))
        with self._lock:  # a walking one's, at its first command (``_command``)
            self._unprepared = walker.orbit if stoppable and not standing else None
        if standing:
            with self._lock:
                self.follower, self._standing, pending = None, walker, self._pending
                self._grid = walker.grid
            self.node.get_logger().info(
                "speed command: the robot stands; a command to walk starts it onto its gait (the kept start)" if startable
                else "speed command: the robot stands; a command to walk is refused (no start is kept for its gait)")
            if pending is not None:
                self._command(*pending)
            return
        self._follow(walker, stamp_ns)

    def _follow(self, walker: Walker, stamp_ns: int) -> None:
        """Make the follower of ``walker``'s gait and publish its envelope stamped ``stamp_ns`` (ns);
        a command that came before is walked then."""
        source = self._source
        follower, note = follower_for(walker, DEFAULTS, self.rule, self.max_change, source, self.max_curvature,
                                      self.max_curvature_change)
        if note:
            self.node.get_logger().warn(f"speed command: {note}")
        self.node.get_logger().info(f"speed command: {follower.rule.describe()}; envelope {follower.envelope.describe()}")
        self.pub_envelope.publish(envelope_msg(follower.envelope, follower.rule.describe(), stamp_msg(stamp_ns)),
                                  stamp_ns)
        with self._lock:
            self.follower, self._standing, pending, self._pending = follower, None, self._pending, None
            self._grid = walker.grid
        if pending is not None:
            self._command(*pending)

    def end(self) -> None:
        """The walk ended (a fall, its steps made): commands are ignored and nothing more is said
        of them until a walk starts again (module docstring). Called before the end is reported."""
        with self._lock:
            self.follower, self._standing, self._pending, self._unprepared = None, None, None, None
            self._walk, self._ended = self._walk + 1, True

    def _prepare(self, gait: PlannedOrbit, source: str | None, kinds: tuple[str, ...]) -> threading.Thread:
        """The thread that makes the kept ``kinds`` (start, stop) of ``gait`` ready, on a model of its
        own (Pinocchio's data are the walk thread's); none if the package keeps none of that gait."""
        walk = self._walk

        def prepare() -> None:
            hybrid = None
            for kind in kinds:
                try:
                    hybrid = hybrid or HybridStep(BipedModel.from_params(load_params(source)))
                    plan = kept_plan(hybrid, kind)
                except ValueError:  # none kept for these parameters
                    return
                if plan.why_not(gait):
                    continue
                with self._lock:
                    if self._walk != walk:
                        return
                    if kind == "start":
                        self._start = plan
                    else:
                        self._stop, self._stop_gait = plan, gait

        thread = threading.Thread(target=prepare, name="stop-prepare", daemon=True)
        thread.start()
        return thread

    def on_twist(self, msg: Twist) -> None:
        """A /cmd_vel message: linear.x the commanded speed (m/s), angular.z the yaw rate (rad/s);
        ignored once the walk ended."""
        if self._ended:
            return
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
            self._last, self._lapsed = (self._now_ns(), time.monotonic()), False
            if self.follower is None and self._standing is None:
                self._pending = (msg.linear.x, msg.angular.z)
                return
        self._command(msg.linear.x, msg.angular.z)

    def _command(self, speed: float, yaw_rate: float) -> None:
        standing = self._standing
        if standing is not None:
            if self._startable:  # a start kept: taken before the next phase (``_started``)
                with self._lock:
                    self._start_asked = (speed, yaw_rate) if speed >= STOP_SPEED else None
                return
            if abs(speed) >= STOP_SPEED or yaw_rate:
                self._explain("start", standing.orbit, standing.bm.params,
                              f"speed command {speed:g} m/s, {yaw_rate:g} rad/s refused while standing: cannot start "
                              "from standing onto", "standing on")
            return
        follower = self.follower
        if follower is None:  # the walk ended meanwhile
            return
        with self._lock:
            gait, self._unprepared = self._unprepared, None
        if gait is not None:  # the walk's first command: its kept stop made ready from now
            self._preparing = self._prepare(gait, self._source, ("stop",))
        self._stop_asked = speed < STOP_SPEED  # said from the gait that walks once it is there (before_step)
        if not self._stop_asked:
            self._stop_home = self._stop_waits = False
        elif self._stop is not None or self._preparing is not None:  # walked to the stop's gait (before_step)
            return
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

    def _explain(self, kind: str, orbit: PlannedOrbit, params: BipedParams, what: str, then: str) -> None:
        """A command to ``kind`` ('start' from standing onto ``orbit``, 'stop' from it): plan it
        with the core (once per kind and gait, in a thread: it takes a second or two) and log why
        it cannot be made, as ``what`` the gait: the reason; ``then``."""
        key = (kind, orbit.step_length, orbit.period)
        with self._lock:
            if key in self._explained:
                return
            self._explained.add(key)
            walk = self._walk
        logger, grid = self.node.get_logger(), self._grid

        def plan() -> None:
            reason = why_not(kind, HybridStep(BipedModel.from_params(params)), orbit, grid)
            with self._lock:  # said only while that walk goes on
                if self._walk == walk:
                    logger.warn(f"{what} the gait L = {orbit.step_length:.3f} m, T = {orbit.period:.3f} s: {reason}; "
                                f"{then}")

        threading.Thread(target=plan, name=f"{kind}-plan", daemon=True).start()

    def before_step(self, walker: Walker) -> None:
        """One transition towards the commanded speed and turn, if the walker is not at them, the
        timeout's 0 first if no command came for that long (walker thread); while standing, the start
        that a command asked for."""
        if self._standing is not None and self._start_asked is not None:
            self._started(walker)
            return
        follower = self.follower
        if follower is None:
            return
        with self._lock:
            last, silent = self._last, 0.0
            if last is not None and not self._lapsed:
                silent = (self._now_ns() - last[0]) * 1e-9
                if self._factor > 0:
                    silent = min(silent, self._factor * (time.monotonic() - last[1]))
            lapsed = self.timeout > 0 and silent >= self.timeout
            self._lapsed = self._lapsed or lapsed
        if lapsed:
            self.node.get_logger().warn(
                f"speed command: no /cmd_vel for {silent:.3f} s of simulated time (cmd_vel_timeout {self.timeout:g} s): "
                "taken as 0 m/s, a stop")
            self._command(0.0, 0.0)
        if self._stop_asked and self._preparing is not None:  # the kept stop made ready (2 s from the first command)
            self._preparing.join()
            self._preparing = None
            if self._stop is None:  # none kept for this walk's gait: the slowest gait, and why
                self._command(0.0, 0.0)
        if self._stop_asked and self._stop is not None and self._stopped(walker, follower):
            return
        transition = follower.before_step(walker)
        if transition is not None and transition.failure:
            self.node.get_logger().warn(f"speed command: no transition before step {transition.step}: "
                                        f"{transition.failure}")
        if self._stop_asked and transition is None and follower.curvature == 0.0 and abs(
                follower.speed - follower.commanded) < 1e-9:  # at the slowest gait, straight: the gait that walks
            self._explain("stop", follower.orbit, follower.bm.params, "speed command: cannot stop from",
                          "walking on at the slowest gait")

    def _started(self, walker: Walker) -> None:
        """Start the standing walk onto its gait (the kept start, once ready), then follow the command
        that asked for it (module docstring)."""
        logger = self.node.get_logger()
        if not isinstance(walker.phase, Standing):  # a stop's double support: asked again once it stands
            return
        if self._preparing is not None:
            self._preparing.join()
            self._preparing = None
        with self._lock:
            start, (speed, yaw_rate) = self._start, self._start_asked
        if start is None:
            self._start_asked = None
            self._explain("start", walker.orbit, walker.bm.params, "speed command: cannot start from standing onto",
                          "standing on")
            return
        try:
            walker.start(start)
        except Unsettled as exc:  # a push: the balance brings it back, asked again before the next 0.1 s
            if not self._start_waits:
                self._start_waits = True
                logger.info(f"speed command: {speed:g} m/s: {exc}: standing until it has settled")
            return
        except ValueError as exc:
            self._start_asked = None
            logger.warn(f"speed command: {exc}; standing on")
            return
        self._start_asked, self._start_waits = None, False
        logger.info(f"speed command: {speed:g} m/s: starting onto the gait L = {start.step_length:g} m, T = "
                    f"{start.period:g} s (the kept start: {start.plan.duration:g} s with both feet down, then I^+), "
                    "then following the command")
        with self._lock:
            self._standing, self._pending, self._startable = None, (speed, yaw_rate), False
        self._follow(walker, self._now_ns())

    def _stopped(self, walker: Walker, follower: SpeedFollower) -> bool:
        """Towards the kept stop (module docstring): stop at this step's touchdown if it aims at the
        stop's gait; else back to that gait's speed, then aimed at the gait. True if the follower is
        not to act before this step."""
        stop, gait, logger = self._stop, self._stop_gait, self.node.get_logger()
        if not stop.why_not(walker.orbit) and walker.state.aim.pending is None:
            try:
                walker.stop(stop)
            except Unsettled as exc:  # settling after a push: a few steps more (fourfold a step)
                if not self._stop_waits:
                    self._stop_waits = True
                    logger.info(f"speed command: 0 m/s: {exc}: walking on until the walk has settled")
                return True
            except ValueError as exc:
                logger.warn(f"speed command: {exc}; walking on")
                self._stop = None
                self._command(0.0, 0.0)  # the slowest gait, and why it cannot stop
                return False
            logger.info(f"speed command: 0 m/s: stopping at the touchdown of step {walker.state.step} (the kept stop "
                        f"of the gait L = {stop.step_length:g} m, T = {stop.period:g} s: {stop.plan.duration:g} s with "
                        "both feet down), then standing")
            startable = not kept_why_not("start", gait)  # standing after the stop, a command starts it again
            with self._lock:
                self.follower, self._standing, self._startable = None, walker, startable
            if startable and self._start is None:  # made ready while the stop's double support runs
                self._preparing = self._prepare(gait, self._source, ("start",))
            return True
        home = gait.step_length / gait.period
        if not self._stop_home:
            self._stop_home = True
            follower.command(home, 0.0)
            logger.info(f"speed command: 0 m/s: walking back to {home:.3f} m/s, the speed of the gait the stop is kept "
                        "for, to stop from it")
            return False
        at_home = follower.curvature == 0.0 and abs(follower.speed - home) < 1e-9
        if at_home and walker.state.aim.pending is None:
            walker.retarget(gait)  # the last transition: onto the stop's gait itself
            return True
        return False


def envelope_msg(envelope: Envelope, rule: str, stamp) -> VelocityEnvelope:
    """The VelocityEnvelope message of ``envelope`` (speed rule described by ``rule``)."""
    return VelocityEnvelope(
        header=Header(stamp=stamp, frame_id=BASE_FRAME), min_linear_x=envelope.low, max_linear_x=envelope.high,
        max_curvature=envelope.max_curvature, max_angular_z=envelope.max_curvature * envelope.high,
        max_linear_x_change=envelope.max_change, max_curvature_change=envelope.max_curvature_change,
        follows_linear_y=False, speed_rule=rule, description=envelope.describe())
