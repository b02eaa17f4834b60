"""The simulator node (entry point ``biped-gait-simulator``): walks a planned gait step after
step and publishes it.

Plan: the latest on the planner's ``gait_plan`` topic (``plan_source: topic``) or its own
request to the planner's ``plan_gait`` service (``plan_source: service``, with the node's
``step_length``, ``period``, ``arm_amplitude``, ``mode``; ``arm_amplitude < 0`` asks the
planner's ``optimize_arm_swing`` action for the optimal amplitude first).

Topics (stamps are the walk's simulated time, started at the node's clock):
``/joint_states`` (sensor_msgs/JointState, URDF joint names), ``/odom`` (nav_msgs/Odometry,
pelvis ``base_link`` in ``world``), ``/angular_momentum`` (biped_gait_interfaces/AngularMomentum),
``/gait_events`` (biped_gait_interfaces/GaitEvent), ``/robot_description`` (std_msgs/String,
transient-local). The recording (MCAP, rosbag2 directory under ``record_dir``) holds all of
these and ``/tf``, ``/tf_static`` (tf2_msgs/msg/TFMessage, recorded with its schema: the
type cannot be installed here, so it is not published live), so that Foxglove shows the robot.
"""

from __future__ import annotations

import math
import threading
import time
from datetime import datetime, timezone

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

import rclpy.logging  # after a signal, a logger of no node: rosout is gone with the context

from geometry_msgs.msg import Point, Vector3
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.action import ActionClient
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_msgs.msg import Header, String

from biped_gait_interfaces.action import OptimizeArmSwing
from biped_gait_interfaces.msg import AngularMomentum, GaitEvent, GaitPlan
from biped_gait_interfaces.srv import PlanGait

from ..boundary import GaitMode
from ..model import BipedModel
from ..params import load_params
from ..walk import Walker
from ..world import BASE_FRAME, WORLD_FRAME, WorldView
from .conversions import MODE_TO_MSG, result_from_plan
from .planner_node import LATCHED
from .process import run_node
from .recorder import DEFAULT_CHUNK_SIZE, McapRecorder

NODE_NAME = "biped_gait_simulator"
TF_TYPE = "tf2_msgs/msg/TFMessage"


class NoAnswer(RuntimeError):
    """A service or action of the planner did not answer in time."""


class SimulatorNode(Node):
    """Walks plans and publishes joint states, pose, angular momentum and gait events."""

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
        self.fell = False
        self.pub_joints = self.create_publisher(JointState, "/joint_states", 50)
        self.pub_odom = self.create_publisher(Odometry, "/odom", 50)
        self.pub_momentum = self.create_publisher(AngularMomentum, "/angular_momentum", 50)
        self.pub_events = self.create_publisher(GaitEvent, "/gait_events", QoSProfile(depth=100))
        self.pub_description = self.create_publisher(String, "/robot_description", LATCHED)
        if self.source == "topic":
            self.create_subscription(GaitPlan, value("plan_topic"), self._on_plan, LATCHED, callback_group=self._group)
        self.plan_client = self.create_client(PlanGait, value("plan_service"), callback_group=self._group)
        self.optimize_client = ActionClient(self, OptimizeArmSwing, value("optimize_action"), callback_group=self._group)
        self.recorder: McapRecorder | None = None
        if value("record"):
            stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S_%f")
            self.recorder = McapRecorder(value("record_dir"), f"walk_{stamp}", chunk_size=value("chunk_size"))
            self.get_logger().info(f"recording to {self.recorder.bag_dir}")
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
        self.declare_parameter("record", True, desc("record everything published, and /tf, to MCAP"))
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
        """The future's result; ``NoAnswer`` after ``timeout`` s or when the node stops."""
        deadline = time.monotonic() + timeout
        while not future.done():
            if self._stop.is_set() or time.monotonic() > deadline:
                raise NoAnswer(f"no answer from {what}")
            time.sleep(0.002)
        return future.result()

    def _request_plan(self) -> GaitPlan:
        value = lambda name: self.get_parameter(name).value  # noqa: E731
        mode = MODE_TO_MSG[GaitMode.parse(value("mode"))]
        if not self.plan_client.wait_for_service(timeout_sec=30.0):
            raise RuntimeError(f"the planner service {value('plan_service')} is not available")
        alpha = value("arm_amplitude")
        if alpha < 0:
            if not self.optimize_client.wait_for_server(timeout_sec=30.0):
                raise RuntimeError("the planner's optimize_arm_swing action is not available")
            goal = OptimizeArmSwing.Goal(step_length=value("step_length"), period=value("period"), mode=mode,
                                         alpha_min=0.0, alpha_max=math.radians(45.0), params=value("params"))
            handle = self._wait(self.optimize_client.send_goal_async(goal), "optimize_arm_swing")
            result = self._wait(handle.get_result_async(), "optimize_arm_swing").result
            if not result.success:
                raise RuntimeError(f"arm-swing optimization failed: {result.message}")
            alpha = result.alpha_opt
            self.get_logger().info(f"optimal arm amplitude {math.degrees(alpha):.2f} deg: {result.message}")
        request = PlanGait.Request(step_length=value("step_length"), period=value("period"), arm_amplitude=alpha,
                                   mode=mode, params=value("params"))
        response = self._call_plan(request)
        if not response.success:
            raise RuntimeError(f"the planner refused: {response.message}")
        return response.plan

    def _call_plan(self, request: PlanGait.Request, attempts: int = 5, patience: float = 10.0) -> PlanGait.Response:
        """Call plan_gait, sending again when no answer comes: right after discovery a DDS
        response can be lost (the server has not yet matched our reader). The call is
        idempotent (and answered from the planner's cache)."""
        for attempt in range(1, attempts + 1):
            future = self.plan_client.call_async(request)
            try:
                return self._wait(future, "plan_gait", patience)
            except NoAnswer:
                self.plan_client.remove_pending_request(future)
                if self._stop.is_set():
                    raise
            self.get_logger().warn(f"no answer from plan_gait in {patience:g} s (attempt {attempt}/{attempts})")
        raise RuntimeError(f"no answer from plan_gait after {attempts} attempts")

    def _obtain_plan(self) -> GaitPlan:
        if self.source == "service":
            return self._request_plan()
        while not self._plan_ready.wait(0.1):
            if self._stop.is_set():
                raise RuntimeError("stopped before a plan arrived")
        return self._latest_plan

    # The walk -----------------------------------------------------------------------------
    def _run(self) -> None:
        try:
            plan = self._obtain_plan()
            self._walk(plan)
        except Exception as exc:  # noqa: BLE001  reported, and the node stays up for inspection
            if self._stopping():
                return  # SIGINT/SIGTERM shut the context down under a publish: a stop, not a fall
            self.fell = True
            self.get_logger().error(f"walk aborted: {exc}")
            self._event(GaitEvent.FALL, 0, "", 0.0, message=str(exc), stamp=self.get_clock().now())
        finally:
            self.finished.set()
            if self.get_parameter("exit_when_done").value:
                self.executor_shutdown()

    def _stopping(self) -> bool:
        return self._stop.is_set() or not self.context.ok()

    def executor_shutdown(self) -> None:
        """End the process's spin (the node's ``exit_when_done``)."""
        self.context.try_shutdown()

    def _walk(self, plan_msg: GaitPlan) -> None:
        wanted = self.get_parameter("wait_for_subscribers").value
        while self.pub_joints.get_subscription_count() < wanted:
            if self._stopping():
                return
            time.sleep(0.01)
        result = result_from_plan(plan_msg)
        bm = BipedModel.from_params(load_params(plan_msg.params or None))
        walker = Walker(bm, result, self.rate, reaim=self.get_parameter("reaim").value)
        view = WorldView(bm)
        start = self.get_clock().now()
        wall0 = time.monotonic()
        self._publish_description(view, start)
        self.get_logger().info(
            f"walking L = {result.step_length:g} m, T = {result.period:g} s, alpha = {math.degrees(result.arm_amplitude):.2f} deg "
            f"({result.mode}), {self.steps or 'unlimited'} steps at {self.rate:g} Hz, real-time factor {self.rtf:g}")
        while not self._stopping() and (self.steps == 0 or walker.state.step < self.steps):
            side, foot, step = walker.state.stance_side, walker.state.stance_foot.copy(), walker.state.step
            outcome = walker.walk_step()
            for sample in outcome.samples:
                if self._stopping():
                    return
                if self.rtf > 0:
                    delay = wall0 + sample.t / self.rtf - time.monotonic()
                    if delay > 0:
                        time.sleep(delay)
                self._publish_sample(view, sample, side, foot, step, start)
            td = outcome.touchdown
            if td is None:
                self.fell = True
                t = outcome.samples[-1].t if outcome.samples else walker.state.t
                self.get_logger().error(f"the robot fell in step {step}: {outcome.fall}")
                self._event(GaitEvent.FALL, step, side, t - walker.state.t, message=outcome.fall,
                            stamp=start + _duration(t))
                return
            self._event(GaitEvent.TOUCHDOWN, step, walker.state.stance_side, td.t_step, td=td, stamp=start + _duration(td.t),
                        message=f"touchdown of step {step}")
        self._event(GaitEvent.FINISHED, walker.state.step, walker.state.stance_side, 0.0,
                    message=f"walked {walker.state.step} steps", stamp=start + _duration(walker.state.t))
        wall = time.monotonic() - wall0
        self.get_logger().info(f"walk finished: {walker.state.step} steps, {walker.state.t:.3f} s simulated in "
                               f"{wall:.3f} s wall time (real-time factor {walker.state.t / wall:.2f})")

    # Publishing ---------------------------------------------------------------------------
    def _publish(self, publisher, msg, stamp_ns: int, transient_local: bool = False) -> None:
        publisher.publish(msg)
        if self.recorder is not None:
            self.recorder.write(publisher.topic_name, msg, stamp_ns, transient_local)

    def _publish_description(self, view: WorldView, start: Time) -> None:
        stamp_ns = start.nanoseconds
        self._publish(self.pub_description, String(data=view.urdf), stamp_ns, transient_local=True)
        if self.recorder is not None:
            header = {"stamp": _stamp_dict(stamp_ns), "frame_id": ""}
            self.recorder.write("/tf_static", {"transforms": [_tf_dict(t, header) for t in view.static_transforms()]},
                                stamp_ns, transient_local=True, datatype=TF_TYPE)

    def _publish_sample(self, view: WorldView, sample, side: str, foot, step: int, start: Time) -> None:
        stamp = start + _duration(sample.t)
        stamp_ns = stamp.nanoseconds
        world = view.state(sample.q, sample.qd, side, foot)
        header = Header(stamp=stamp.to_msg(), frame_id=WORLD_FRAME)
        self._publish(self.pub_joints, JointState(
            header=Header(stamp=header.stamp), name=list(world.joint_names),
            position=world.joint_positions, velocity=world.joint_velocities), stamp_ns)
        odom = Odometry(header=header, child_frame_id=BASE_FRAME)
        pose = odom.pose.pose
        pose.position = Point(x=float(world.pelvis_position[0]), y=float(world.pelvis_position[1]), z=float(world.pelvis_position[2]))
        qx, qy, qz, qw = (float(v) for v in world.pelvis_quaternion)
        pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = qx, qy, qz, qw
        odom.twist.twist.linear = _vector(world.pelvis_linear_velocity)
        odom.twist.twist.angular = _vector(world.pelvis_angular_velocity)
        self._publish(self.pub_odom, odom, stamp_ns)
        self._publish(self.pub_momentum, AngularMomentum(
            header=header, stance_foot=_point(world.stance_foot), about_stance_foot=_vector(world.momentum_about_foot),
            com=_point(world.com), about_com=_vector(world.momentum_about_com), step=step, stance_side=side), stamp_ns)
        if self.recorder is not None:
            tf_header = {"stamp": _stamp_dict(stamp_ns), "frame_id": ""}
            self.recorder.write("/tf", {"transforms": [_tf_dict(t, tf_header) for t in world.link_transforms]},
                                stamp_ns, datatype=TF_TYPE)

    def _event(self, kind: int, step: int, side: str, time_in_step: float, stamp: Time, message: str = "", td=None) -> None:
        msg = GaitEvent(header=Header(stamp=stamp.to_msg(), frame_id=WORLD_FRAME), kind=kind, step=step,
                        stance_side=side, time_in_step=time_in_step, message=message)
        if td is not None:
            msg.i_minus, msg.i_plus = [float(v) for v in td.i_minus], [float(v) for v in td.i_plus]
            msg.effort_cost, msg.state_error, msg.velocity_miss = td.W, td.state_error, td.velocity_miss
        self._publish(self.pub_events, msg, stamp.nanoseconds)

    def close(self) -> None:
        """Stop the walk and finalize the recording (shutdown, SIGINT and SIGTERM included)."""
        self._stop.set()
        self._worker.join(timeout=10.0)
        if self.recorder is not None:
            self.recorder.close()
            rclpy.logging.get_logger("biped_gait.recorder").info(f"{self.get_name()}: recording finalized: {self.recorder.bag_dir}")


def _duration(seconds: float):
    from rclpy.duration import Duration

    return Duration(nanoseconds=int(round(seconds * 1e9)))


def _stamp_dict(stamp_ns: int) -> dict:
    return {"sec": stamp_ns // 1_000_000_000, "nanosec": stamp_ns % 1_000_000_000}


def _tf_dict(t, header: dict) -> dict:
    """A geometry_msgs/TransformStamped as a dict (for the TFMessage record)."""
    x, y, z = (float(v) for v in t.translation)
    qx, qy, qz, qw = (float(v) for v in t.quaternion)
    return {"header": dict(header, frame_id=t.parent), "child_frame_id": t.child,
            "transform": {"translation": {"x": x, "y": y, "z": z}, "rotation": {"x": qx, "y": qy, "z": qz, "w": qw}}}


def _vector(v) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _point(v) -> Point:
    return Point(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def main(args: list[str] | None = None) -> int:
    """Entry point ``biped-gait-simulator``: walk, publish and record until done or stopped.
    Exit status 1 if the robot fell (or the walk could not start), 0 otherwise."""
    nodes: list[SimulatorNode] = []

    def make() -> SimulatorNode:
        nodes.append(SimulatorNode())
        return nodes[-1]

    status = run_node(make, "biped-gait-simulator", args=args)
    return 1 if status == 0 and nodes and nodes[0].fell else status
