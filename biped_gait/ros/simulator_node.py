"""The simulator node (entry point ``biped-gait-simulator``): fetches a plan, walks it with the
core's ``Walk``, paces it against the wall clock, and publishes and records what it yields.

Plan: the latest on the planner's ``gait_plan`` topic (``plan_source: topic``) or its own
request to the planner's ``plan_gait`` service (``plan_source: service``, with the node's
``step_length``, ``period``, ``arm_amplitude``, ``mode``; ``arm_amplitude < 0`` asks the
planner's ``optimize_arm_swing`` action for the optimal amplitude first).

Topics (stamps are the walk's simulated time, started at the node's clock):
``/joint_states`` (sensor_msgs/JointState, URDF joint names), ``/odom`` (nav_msgs/Odometry,
pelvis ``base_link`` in ``world``), ``/angular_momentum`` (biped_gait_interfaces/AngularMomentum),
``/gait_events`` (biped_gait_interfaces/GaitEvent), ``/tf`` (the URDF's moving joints and the
pelvis in ``world``), and transient-local ``/robot_description`` (std_msgs/String) and
``/tf_static``. The recording (MCAP, rosbag2 directory under ``record_dir``) holds the same
bytes as were published.

Outcomes: the walk finished (exit status 0), the robot fell, the walk could not start (a plan
that cannot be walked), or no plan came (the planner did not answer, or refused): each its own
event and log line, and exit status 1.
"""

from __future__ import annotations

import math
import threading
import time
from datetime import datetime, timezone

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

import rclpy.logging  # after a signal, a logger of no node: rosout is gone with the context

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.action import ActionClient
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from sensor_msgs.msg import JointState
from nav_msgs.msg import Odometry
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from biped_gait_interfaces.action import OptimizeArmSwing
from biped_gait_interfaces.msg import AngularMomentum, GaitEvent, GaitPlan
from biped_gait_interfaces.srv import PlanGait

from ..core.configurations import GaitMode
from ..core.pacing import Pacer
from ..core.settings import DEFAULTS
from ..core.walk import CouldNotStart, Fell, Finished, Sample, Touchdown, Walk
from ..recording import topics
from ..recording.writer import DEFAULT_CHUNK_SIZE, McapRecorder
from .conversions import MODE_TO_MSG, orbit_from_msg
from .process import run_node
from .qos import EVENTS, LATCHED, STREAM
from .recorded import RecordedPublisher
from .walk_messages import event_msg, joint_state_msg, momentum_msg, odometry_msg, stamp_msg, tf_msg

NODE_NAME = "biped_gait_simulator"


class NoPlan(RuntimeError):
    """No plan to walk: the planner did not answer in time, refused, or the node stopped."""


class SimulatorNode(Node):
    """Walks plans and publishes joint states, pose, angular momentum, transforms and events."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        self._declare_parameters()
        value = lambda name: self.get_parameter(name).value  # noqa: E731
        self.source = value("plan_source")
        if self.source not in ("topic", "service"):
            raise ValueError(f"plan_source must be 'topic' or 'service', got {self.source!r}")
        self.rate = value("publish_rate")
        self.rtf = value("real_time_factor")
        self.steps = value("steps")
        self._group = ReentrantCallbackGroup()
        self._latest_plan: GaitPlan | None = None
        self._plan_ready = threading.Event()
        self._stop = threading.Event()
        self.finished = threading.Event()
        self.failed = False
        self.recorder: McapRecorder | None = None
        if value("record"):
            stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S_%f")
            self.recorder = McapRecorder(value("record_dir"), f"walk_{stamp}", chunk_size=value("chunk_size"))
            self.get_logger().info(f"recording to {self.recorder.bag_dir}")
        publisher = lambda msg_type, topic, qos: RecordedPublisher(self, msg_type, topic, qos, self.recorder)  # noqa: E731
        self.pub_joints = publisher(JointState, topics.JOINT_STATES, STREAM)
        self.pub_odom = publisher(Odometry, topics.ODOM, STREAM)
        self.pub_momentum = publisher(AngularMomentum, topics.ANGULAR_MOMENTUM, STREAM)
        self.pub_tf = publisher(TFMessage, topics.TF, STREAM)
        self.pub_events = publisher(GaitEvent, topics.GAIT_EVENTS, EVENTS)
        self.pub_description = publisher(String, topics.ROBOT_DESCRIPTION, LATCHED)
        self.pub_tf_static = publisher(TFMessage, topics.TF_STATIC, LATCHED)
        if self.source == "topic":
            self.create_subscription(GaitPlan, value("plan_topic"), self._on_plan, LATCHED, callback_group=self._group)
        self.plan_client = self.create_client(PlanGait, value("plan_service"), callback_group=self._group)
        self.optimize_client = ActionClient(self, OptimizeArmSwing, value("optimize_action"), callback_group=self._group)
        self._worker = threading.Thread(target=self._run, name="walker", daemon=True)
        self._worker.start()

    def _declare_parameters(self) -> None:
        def desc(text: str, **kw) -> ParameterDescriptor:
            return ParameterDescriptor(description=text, read_only=True, **kw)

        positive = [FloatingPointRange(from_value=1.0, to_value=100000.0)]
        self.declare_parameter("plan_source", "service", desc("'service': request a plan; 'topic': walk the latest plan published"))
        self.declare_parameter("plan_service", "/biped_gait_planner/plan_gait", desc("the planner's PlanGait service"))
        self.declare_parameter("plan_topic", "/biped_gait_planner/gait_plan", desc("the planner's GaitPlan topic"))
        self.declare_parameter("optimize_action", "/biped_gait_planner/optimize_arm_swing", desc("the planner's action"))
        self.declare_parameter("step_length", 0.45, desc("L (m) of the requested plan"))
        self.declare_parameter("period", 0.45, desc("T (s) of the requested plan"))
        self.declare_parameter("arm_amplitude", math.radians(23.5), desc("alpha (rad); negative: the optimal one"))
        self.declare_parameter("mode", "normal", desc("'normal' or 'anti-normal'"))
        self.declare_parameter("params", "", desc("parameter set of the requested plan; empty: the planner's"))
        self.declare_parameter("steps", 20, desc("steps to walk; 0: until stopped",
                                                 integer_range=[IntegerRange(from_value=0, to_value=1000000, step=1)]))
        self.declare_parameter("real_time_factor", 1.0, desc(
            "simulated seconds per wall second; 0: as fast as possible",
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1000.0)]))
        self.declare_parameter("publish_rate", 500.0, desc("samples per second of simulated time", floating_point_range=positive))
        self.declare_parameter("reaim", True, desc("re-solve each step from the actual state (the open-loop gait is unstable)"))
        self.declare_parameter("record", True, desc("record everything published to MCAP"))
        self.declare_parameter("record_dir", "bags", desc("directory of the recordings"))
        self.declare_parameter("chunk_size", DEFAULT_CHUNK_SIZE, desc(
            "MCAP chunk size (bytes): at most this much is lost if the process is killed",
            integer_range=[IntegerRange(from_value=1024, to_value=64 * 1024 * 1024, step=1)]))
        self.declare_parameter("exit_when_done", False, desc("end the process when the walk ends"))
        self.declare_parameter("wait_for_subscribers", 0, desc(
            "start walking once /joint_states has this many subscribers (discovery can take seconds)",
            integer_range=[IntegerRange(from_value=0, to_value=100, step=1)]))

    # Plan acquisition ---------------------------------------------------------------------
    def _on_plan(self, msg: GaitPlan) -> None:
        self._latest_plan = msg
        self._plan_ready.set()

    def _wait(self, future, what: str, timeout: float = 120.0):
        """The future's result; ``NoPlan`` after ``timeout`` s or when the node stops."""
        deadline = time.monotonic() + timeout
        while not future.done():
            if self._stop.is_set() or time.monotonic() > deadline:
                raise NoPlan(f"no answer from {what}")
            time.sleep(0.002)
        return future.result()

    def _request_plan(self) -> GaitPlan:
        value = lambda name: self.get_parameter(name).value  # noqa: E731
        mode = MODE_TO_MSG[GaitMode.parse(value("mode"))]
        if not self.plan_client.wait_for_service(timeout_sec=30.0):
            raise NoPlan(f"the planner service {value('plan_service')} is not available")
        alpha = value("arm_amplitude")
        if alpha < 0:
            if not self.optimize_client.wait_for_server(timeout_sec=30.0):
                raise NoPlan("the planner's optimize_arm_swing action is not available")
            low, high = DEFAULTS.arm_range
            goal = OptimizeArmSwing.Goal(step_length=value("step_length"), period=value("period"), mode=mode,
                                         alpha_min=low, alpha_max=high, params=value("params"))
            handle = self._wait(self.optimize_client.send_goal_async(goal), "optimize_arm_swing")
            result = self._wait(handle.get_result_async(), "optimize_arm_swing").result
            if not result.success:
                raise NoPlan(f"arm-swing optimization failed: {result.message}")
            alpha = result.alpha_opt
            self.get_logger().info(f"optimal arm amplitude {math.degrees(alpha):.2f} deg: {result.message}")
        request = PlanGait.Request(step_length=value("step_length"), period=value("period"), arm_amplitude=alpha,
                                   mode=mode, params=value("params"))
        response = self._call_plan(request)
        if not response.success:
            raise NoPlan(f"the planner refused: {response.message}")
        return response.plan

    def _call_plan(self, request: PlanGait.Request, attempts: int = 5, patience: float = 10.0) -> PlanGait.Response:
        """Call plan_gait, sending again when no answer comes: right after discovery a DDS
        response can be lost (the server has not yet matched our reader). The call is
        idempotent (and answered from the planner's cache)."""
        for attempt in range(1, attempts + 1):
            future = self.plan_client.call_async(request)
            try:
                return self._wait(future, "plan_gait", patience)
            except NoPlan:
                self.plan_client.remove_pending_request(future)
                if self._stop.is_set():
                    raise
            self.get_logger().warn(f"no answer from plan_gait in {patience:g} s (attempt {attempt}/{attempts})")
        raise NoPlan(f"no answer from plan_gait after {attempts} attempts")

    def _obtain_plan(self) -> GaitPlan:
        if self.source == "service":
            return self._request_plan()
        while not self._plan_ready.wait(0.1):
            if self._stop.is_set():
                raise NoPlan("stopped before a plan arrived")
        return self._latest_plan

    # The walk -----------------------------------------------------------------------------
    def _run(self) -> None:
        try:
            try:
                plan = self._obtain_plan()
            except NoPlan as exc:
                self._not_started(f"no plan: {exc}")
            else:
                self._walk(plan)
        except Exception as exc:  # noqa: BLE001  reported, and the node stays up for inspection
            if not self._stopping():  # SIGINT/SIGTERM shut the context down under a publish: a stop
                self.failed = True
                self.get_logger().error(f"walk aborted: {exc!r}")
        finally:
            self.finished.set()
            if self.get_parameter("exit_when_done").value:
                self.context.try_shutdown()

    def _stopping(self) -> bool:
        return self._stop.is_set() or not self.context.ok()

    def _not_started(self, reason: str) -> None:
        if self._stopping():
            return
        self.failed = True
        self.get_logger().error(f"the walk did not start: {reason}")
        stamp = stamp_msg(self.get_clock().now().nanoseconds)
        self.pub_events.publish(event_msg(GaitEvent.NOT_STARTED, 0, "", 0.0, stamp, reason))

    def _walk(self, plan: GaitPlan) -> None:
        wanted = self.get_parameter("wait_for_subscribers").value
        while self.pub_joints.subscription_count() < wanted:
            if self._stop.wait(0.01) or not self.context.ok():
                return
        walk = Walk(orbit_from_msg(plan), self.rate, self.steps, reaim=self.get_parameter("reaim").value)
        start_ns = self.get_clock().now().nanoseconds
        if walk.world is not None:
            stamp = stamp_msg(start_ns)
            self.pub_description.publish(String(data=walk.world.urdf), start_ns)
            self.pub_tf_static.publish(tf_msg(walk.world.static_transforms(), stamp), start_ns)
        self.get_logger().info(
            f"walking L = {plan.step_length:g} m, T = {plan.period:g} s, alpha = {math.degrees(plan.arm_amplitude):.2f} deg "
            f"({walk.orbit.mode}), {self.steps or 'unlimited'} steps at {self.rate:g} Hz, real-time factor {self.rtf:g}")
        pacer = Pacer(self.rtf)
        for item in walk:
            if isinstance(item, Sample):
                if not pacer.wait(item.t, self._stop) or not self.context.ok():
                    return
                self._publish_sample(item, start_ns)
            elif isinstance(item, Touchdown):
                self._event(GaitEvent.TOUCHDOWN, item.step, item.next_stance_side, item.t_step, start_ns, item.t,
                            f"touchdown of step {item.step}", item)
            elif isinstance(item, Fell):
                self.failed = True
                self.get_logger().error(f"the robot fell in step {item.step}: {item.reason}")
                self._event(GaitEvent.FALL, item.step, item.stance_side, item.time_in_step, start_ns, item.t, item.reason)
            elif isinstance(item, Finished):
                self._event(GaitEvent.FINISHED, item.steps, item.stance_side, 0.0, start_ns, item.t,
                            f"walked {item.steps} steps")
                wall = pacer.elapsed()
                self.get_logger().info(f"walk finished: {item.steps} steps, {item.t:.3f} s simulated in {wall:.3f} s "
                                       f"wall time (real-time factor {item.t / wall:.2f})")
            elif isinstance(item, CouldNotStart):
                self._not_started(item.reason)

    # Publishing ---------------------------------------------------------------------------
    def _publish_sample(self, sample: Sample, start_ns: int) -> None:
        stamp_ns = start_ns + round(sample.t * 1e9)
        stamp = stamp_msg(stamp_ns)
        world = sample.world
        self.pub_joints.publish(joint_state_msg(world, stamp), stamp_ns)
        self.pub_odom.publish(odometry_msg(world, stamp), stamp_ns)
        self.pub_momentum.publish(momentum_msg(world, stamp, sample.step, sample.stance_side), stamp_ns)
        self.pub_tf.publish(tf_msg(world.link_transforms, stamp), stamp_ns)

    def _event(self, kind: int, step: int, side: str, time_in_step: float, start_ns: int, t: float, message: str,
               touchdown: Touchdown | None = None) -> None:
        stamp_ns = start_ns + round(t * 1e9)
        self.pub_events.publish(event_msg(kind, step, side, time_in_step, stamp_msg(stamp_ns), message, touchdown),
                                stamp_ns)

    def close(self) -> None:
        """Stop the walk and finalize the recording (shutdown, SIGINT and SIGTERM included)."""
        self._stop.set()
        self._worker.join(timeout=10.0)
        if self.recorder is not None:
            self.recorder.close()
            rclpy.logging.get_logger("biped_gait.recorder").info(f"{self.get_name()}: recording finalized: {self.recorder.bag_dir}")


def main(args: list[str] | None = None) -> int:
    """Entry point ``biped-gait-simulator``: walk, publish and record until done or stopped.
    Exit status 1 if the walk did not finish (a fall, no plan, a plan that cannot be walked)."""
    nodes: list[SimulatorNode] = []

    def make() -> SimulatorNode:
        nodes.append(SimulatorNode())
        return nodes[-1]

    status = run_node(make, "biped-gait-simulator", args=args)
    return 1 if status == 0 and nodes and nodes[0].failed else status
