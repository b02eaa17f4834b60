"""The simulator node walking circles over Fast DDS with the 13-DOF set (aoustin2013-hips): a
full circle from ``turn_radius`` comes back to its start in the recorded /odom; /cmd_vel's
angular.z turns the walk at the commanded yaw rate after its per-step ramp, a command beyond the
envelope is clamped with a warning, and the envelope is latched on ~/velocity_envelope; the
tutorial's turn under the default speed rule, at real time; and that turn, then silence: the walk
slows to the slowest gait and walks on for 30 s of simulated time."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import math
import re
from collections.abc import Callable

import numpy as np
from geometry_msgs.msg import Twist, Vector3
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from biped_gait.ros.client import ClientSide
from biped_gait_interfaces.msg import GaitEvent, VelocityEnvelope

from .ros_helpers import planner_process, read_bag, start_simulator

pytestmark = pytest.mark.ros

PLANNER = "turning_test_planner"
L = 0.45
ALPHA = math.radians(20.0)
STRIDES = 14
R_CIRCLE = STRIDES * 2 * L / (2 * math.pi)  # m: 14 strides of 2 L / R make a full turn


@pytest.fixture(scope="module")
def planner_node(tmp_path_factory):
    with planner_process(PLANNER, tmp_path_factory.mktemp("turning_planner")) as proc:
        yield proc


def stamp(header) -> float:
    """A header's stamp (s)."""
    return header.stamp.sec + 1e-9 * header.stamp.nanosec


def yaw(orientation) -> float:
    """The heading (rad) of a quaternion (a rotation about the vertical and small tilts)."""
    q = orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def turns(where) -> tuple[list[float], Callable[[float], float]]:
    """The recorded walk under ``where``: its touchdown instants (s) and its heading (rad, unwrapped)
    at a time, from /odom."""
    [bag] = list((where / "bags").iterdir())
    topics = read_bag(bag)
    odom = [m for _, m in topics["/odom"]]
    stamps = np.array([stamp(m.header) for m in odom])
    headings = np.unwrap([yaw(m.pose.pose.orientation) for m in odom])
    touchdowns = [m for _, m in topics["/gait_events"] if m.kind == GaitEvent.TOUCHDOWN]
    return ([stamp(m.header) for m in touchdowns],
            lambda t: float(headings[np.argmin(np.abs(stamps - t))]))


def test_a_circle_from_turn_radius_closes_on_its_start(planner_node, tmp_path):
    """The circle of 14 strides (28 steps) and one step more: the sample at the start of step 28
    has the pelvis where the walk started, heading turned by 2 pi (the plan walked to numerical
    precision: periodic modulo the rotation, and the full circle's rotation is the identity)."""
    proc = start_simulator(tmp_path, PLANNER, f"steps:={2 * STRIDES + 1}", "real_time_factor:=0.0",
                           "exit_when_done:=true", "publish_rate:=50.0", "params:=aoustin2013-hips",
                           f"arm_amplitude:={ALPHA}", f"turn_radius:={R_CIRCLE}")
    assert proc.wait(timeout=300) == 0, (tmp_path / "biped-gait-simulator.log").read_text()
    [bag] = list((tmp_path / "bags").iterdir())
    topics = read_bag(bag)
    touchdowns = [m for _, m in topics["/gait_events"] if m.kind == GaitEvent.TOUCHDOWN]
    assert len(touchdowns) == 2 * STRIDES + 1 and max(e.state_error for e in touchdowns) < 1e-8
    odom = [m for _, m in topics["/odom"]]
    assert odom[0].header.frame_id == "odom" and odom[0].child_frame_id == "base_link"
    stamps = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in odom])
    circle = sum(e.time_in_step for e in touchdowns[:2 * STRIDES])  # s: 28 steps of 0.45 s, to rounding
    k = int(np.argmin(np.abs(stamps - (stamps[0] + circle))))
    assert stamps[k] - stamps[0] == pytest.approx(circle, abs=1e-6)
    first, again = odom[0].pose.pose, odom[k].pose.pose
    gap = math.dist((first.position.x, first.position.y, first.position.z),
                    (again.position.x, again.position.y, again.position.z))
    headings = np.unwrap([yaw(m.pose.pose.orientation) for m in odom])
    turned = headings[k] - headings[0]
    print(f"\nafter a circle of R = {R_CIRCLE:.4f} m ({circle:.4f} s): the pelvis {gap:.2e} m from its start, "
          f"heading turned {turned:.9f} rad")
    assert gap < 1e-6
    assert turned == pytest.approx(2 * math.pi, abs=1e-6)


def test_cmd_vel_angular_z_turns_the_walk_at_the_commanded_rate(planner_node, tmp_path):
    """From the straight gait, /cmd_vel (1.0 m/s, 0.8 rad/s): beyond the envelope (curvature
    0.5 1/m), clamped to 0.5 rad/s with a warning; the curvature ramps by 0.1 1/m per step, and
    from then on the recorded /odom heading turns at 0.5 rad/s. The envelope is latched."""
    side = ClientSide("turning_test_client")
    envelopes: list[VelocityEnvelope] = []
    events: list[GaitEvent] = []
    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
        node.create_subscription(VelocityEnvelope, "/biped_gait_simulator/velocity_envelope", envelopes.append, latched)
        node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        node.create_subscription(JointState, "/joint_states", lambda m: None, 10)
        timer = node.create_timer(0.2, lambda: pub.publish(Twist(linear=Vector3(x=1.0), angular=Vector3(z=0.8))))
        proc = start_simulator(tmp_path, PLANNER, "steps:=16", "real_time_factor:=0.0", "exit_when_done:=true",
                               "publish_rate:=50.0", "params:=aoustin2013-hips", f"arm_amplitude:={ALPHA}",
                               "speed_rule:=cadence", "wait_for_subscribers:=1",
                               "cmd_vel_timeout:=0.0")  # unpaced: the simulated clock outruns the commands
        side.wait(lambda: proc.poll() is not None, 300.0)  # spinning: the commands go on
        assert proc.wait() == 0, (tmp_path / "biped-gait-simulator.log").read_text()
        side.wait(lambda: bool(envelopes), 10.0)
        timer.cancel()
    finally:
        side.close()
    [envelope] = envelopes[-1:]
    assert envelope.max_curvature == 0.5 and envelope.max_curvature_change == pytest.approx(0.1)
    assert envelope.max_angular_z == pytest.approx(0.5 * envelope.max_linear_x)
    assert envelope.min_linear_x < 1.0 < envelope.max_linear_x and not envelope.follows_linear_y
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert "is outside the envelope" in log and "clamped to 1.000 m/s, 0.500 rad/s" in log
    assert not [e for e in events if e.kind == GaitEvent.FALL]
    times, heading_at = turns(tmp_path)
    rates = [(heading_at(b) - heading_at(a)) / (b - a) for a, b in zip(times, times[1:])]
    print("\nyaw rate per step from /odom (rad/s): " + " ".join(f"{r:.3f}" for r in rates))
    # The curvature ramps 0.1 1/m per step from the first step: at 0.5 1/m from the fifth
    # touchdown on; one stride averages the inner and outer step.
    steady = (heading_at(times[14]) - heading_at(times[8])) / (times[14] - times[8])
    assert steady == pytest.approx(0.5, rel=0.02)
    assert all(r <= 0.5 * 1.15 for r in rates[:4])  # no faster than the ramp allows


def test_the_tutorials_turn_under_the_default_speed_rule(planner_node, tmp_path):
    """docs/tutorial.md section 5 as written: the 13-DOF set at alpha = 0.349 rad, the default
    speed rule (least effort per metre), real time, /cmd_vel Twist(1.0, 0.4). The curvature ramps
    0.1 1/m per step to 0.4 1/m (the period held while turning: the strides of one period), no
    transition fails or is retried, and the recorded heading turns at 0.4 rad/s. The walk's
    real-time factor is printed (it was 1/20 when the rule picked a stride it could not reach
    and tried it again at every step)."""
    side = ClientSide("tutorial_turn_client")
    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(JointState, "/joint_states", lambda m: None, 10)
        timer = node.create_timer(0.1, lambda: pub.publish(Twist(linear=Vector3(x=1.0), angular=Vector3(z=0.4))))
        proc = start_simulator(tmp_path, PLANNER, "steps:=14", "exit_when_done:=true", "params:=aoustin2013-hips",
                               "arm_amplitude:=0.349", "wait_for_subscribers:=1")
        side.wait(lambda: proc.poll() is not None, 300.0)  # spinning: the commands go on
        timer.cancel()
    finally:
        side.close()
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert proc.returncode == 0, log
    assert "speed command: least effort per metre" in log and "no transition" not in log, log
    rtf = float(re.search(r"real-time factor ([\d.]+)\)", log).group(1))
    times, heading_at = turns(tmp_path)
    rates = [(heading_at(b) - heading_at(a)) / (b - a) for a, b in zip(times, times[1:])]
    print(f"\nyaw rate per step from /odom (rad/s): {' '.join(f'{r:.3f}' for r in rates)}; the walk's real-time "
          f"factor {rtf:.2f} (paced at 1)")
    assert len(times) == 14
    steady = (heading_at(times[13]) - heading_at(times[7])) / (times[13] - times[7])  # three strides at 0.4 1/m
    assert steady == pytest.approx(0.4, rel=0.02)
    assert all(r <= 0.4 * 1.15 for r in rates[:4])  # no faster than the ramp allows


def test_the_tutorials_turn_then_silence_walks_on_at_the_slowest_gait(planner_node, tmp_path):
    """docs/tutorial.md section 5 with the hips, then the publisher stops: Twist(1.0, 0.4) for 7 s
    of simulated time, then nothing: the timeout (0.5 s) takes it as 0, clamped to the envelope's
    slowest gait; the walk straightens and slows there through transition steps (more of them
    where the steering cannot follow a change in one) and walks on without a fall for 30 s of
    simulated time after the silence, at the slowest speed. (It fell about 3 s after the
    silence, in step 40, when the slowest gaits were at T = 0.65 s, where the steering's pitch
    has no authority over the momentum about the feet line.) Asked at twice real time
    (``real_time_factor:=2.0``), it runs as fast as the walk computes: measured 0.89 of real time
    on the project's 2-core machine (2026-12-06), so its time is the walk's computing, not pacing."""
    side = ClientSide("tutorial_silence_client")
    walk_times: list[float] = []  # s: the simulated time of each /odom received
    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(JointState, "/joint_states", lambda m: None, 10)
        node.create_subscription(Odometry, "/odom", lambda m: walk_times.append(stamp(m.header)), 100)
        timer = node.create_timer(0.1, lambda: pub.publish(Twist(linear=Vector3(x=1.0), angular=Vector3(z=0.4))))
        proc = start_simulator(tmp_path, PLANNER, "steps:=100", "exit_when_done:=true", "params:=aoustin2013-hips",
                               "arm_amplitude:=0.349", "wait_for_subscribers:=1", "real_time_factor:=2.0",
                               "publish_rate:=50.0")
        side.wait(lambda: proc.poll() is not None or bool(walk_times) and walk_times[-1] - walk_times[0] >= 7.0, 120.0)
        timer.cancel()
        silence = walk_times[-1]  # s: the last command's simulated time, to a sample
        side.wait(lambda: proc.poll() is not None, 400.0)
    finally:
        side.close()
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert proc.returncode == 0, log
    assert "no /cmd_vel for" in log and "no transition" not in log, log
    [bag] = list((tmp_path / "bags").iterdir())
    topics = read_bag(bag)
    events = [m for _, m in topics["/gait_events"]]
    assert not [e for e in events if e.kind == GaitEvent.FALL]
    times = [stamp(e.header) for e in events if e.kind == GaitEvent.TOUCHDOWN]
    [(_, envelope)] = topics["/biped_gait_simulator/velocity_envelope"]
    odom = [m for _, m in topics["/odom"]]
    stamps = np.array([stamp(m.header) for m in odom])
    where = np.array([(m.pose.pose.position.x, m.pose.pose.position.y) for m in odom])
    at = lambda t: where[np.argmin(np.abs(stamps - t))]  # noqa: E731
    speed = float(np.linalg.norm(at(times[-1]) - at(times[-7])) / (times[-1] - times[-7]))  # three straight strides
    print(f"\n{len(times)} steps, {times[-1] - silence:.1f} s of simulated time after the last command, no fall; "
          f"the last three strides at {speed:.4f} m/s (the envelope's slowest {envelope.min_linear_x:.3f} m/s)")
    assert len(times) == 100 and times[-1] - silence >= 30.0
    # /odom at 50 Hz: each end of the three strides (2.5 s) within 0.01 s, 0.8 % of the speed
    assert speed == pytest.approx(envelope.min_linear_x, rel=0.02)
