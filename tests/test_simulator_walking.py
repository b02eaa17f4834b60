"""The simulator node pushed and steered over Fast DDS, with a planner of its own: a push below
the limit the push study finds is recovered (back within 1e-3 of the orbit 10 steps later), one
well above it is a fall reported with its step and time; a ramp of /cmd_vel changes the speed
measured from /odom to within 2 % of the command, with no fall; /gait_phase follows the
biped_interfaces/Phase convention."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import time
from pathlib import Path

import numpy as np
from geometry_msgs.msg import Twist, Vector3
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.ros.client import ClientSide
from biped_gait.studies.push_study import PHASE, RECOVERY_STEPS, RECOVERY_TOLERANCE, STUDY_DIRECTIONS, largest_push
from biped_gait_interfaces.msg import GaitEvent, GaitPhase
from biped_gait_interfaces.srv import Push

from .conftest import DEFAULT_REQUEST
from .ros_helpers import read_bag, planner_process, start_simulator, stop_node

pytestmark = pytest.mark.ros

PLANNER = "walking_test_planner"
SIMULATOR = "biped_gait_simulator"


@pytest.fixture(scope="module")
def planner_node(tmp_path_factory):
    with planner_process(PLANNER, tmp_path_factory.mktemp("walking_planner")) as proc:
        yield proc


@pytest.fixture(scope="module")
def forward_limit(planner) -> float:
    """The push study's largest forward push recovered (N s, mid-step) for the simulator's
    default gait (L = T = 0.45, alpha = 23.5 deg, normal)."""
    gait = planner.plan(DEFAULT_REQUEST)
    limit = largest_push(planner.hybrid, PlannedOrbit.of(gait), "forward", STUDY_DIRECTIONS["forward"], PHASE)
    print(f"\nlargest forward push recovered: {limit.limit:.3f} N s (first failure {limit.first_failure:.3f} N s)")
    return limit.limit


def simulator(where: Path, *params: str):
    return start_simulator(where, PLANNER, *params)


def test_a_push_below_the_limit_is_recovered(planner_node, forward_limit, tmp_path):
    """Half the limit through ~/push while walking: the push event, no fall, and every touchdown
    from 10 steps after the pushed one within 1e-3 of the plan."""
    magnitude = 0.5 * forward_limit
    side = ClientSide("push_test_client")
    events: list[GaitEvent] = []
    try:
        side.node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        side.node.create_subscription(JointState, "/joint_states", lambda m: None, 10)  # the walk waits for it
        client = side.node.create_client(Push, f"/{SIMULATOR}/push")
        proc = simulator(tmp_path, "steps:=24", "real_time_factor:=2.0", "exit_when_done:=true", "record:=false",
                         "wait_for_subscribers:=1")
        side.connect(client, 60.0)
        side.wait(lambda: any(e.kind == GaitEvent.TOUCHDOWN for e in events), 60.0)
        response = side.call(client, Push.Request(impulse=Vector3(x=magnitude), phase=PHASE))
        assert response.success, response.message
        side.wait(lambda: any(e.kind in (GaitEvent.FINISHED, GaitEvent.FALL) for e in events), 60.0)
        assert proc.wait(timeout=30) == 0
    finally:
        side.close()
    [push] = [e for e in events if e.kind == GaitEvent.PUSH]
    assert push.step == response.step and push.time_in_step == pytest.approx(PHASE * 0.45, abs=1e-9)
    assert not [e for e in events if e.kind == GaitEvent.FALL]
    errors = {e.step: e.state_error for e in events if e.kind == GaitEvent.TOUCHDOWN}
    after = [errors[s] for s in sorted(errors) if s >= push.step + RECOVERY_STEPS]
    print(f"\npush of {magnitude:.3f} N s in step {push.step}: state error at each touchdown "
          + " ".join(f"{errors[s]:.0e}" for s in sorted(errors)))
    assert after and max(after) < RECOVERY_TOLERANCE


def test_a_push_well_above_the_limit_is_a_fall_with_its_step_and_time(planner_node, forward_limit, tmp_path):
    """Three times the limit, scripted in step 2: a FALL event with the step and the time, the
    log line, exit status 1; the push itself on /gait_events before it."""
    magnitude = 3.0 * forward_limit
    proc = simulator(tmp_path, "steps:=20", "real_time_factor:=0.0", "exit_when_done:=true",
                     f"pushes:=2 {PHASE} {magnitude} 0 0")
    assert proc.wait(timeout=120) == 1
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert "the robot fell in step" in log
    [bag] = list((tmp_path / "bags").iterdir())
    events = [m for _, m in read_bag(bag)["/gait_events"]]
    [push] = [e for e in events if e.kind == GaitEvent.PUSH]
    fall = events[-1]
    assert push.step == 2 and fall.kind == GaitEvent.FALL and fall.message
    assert fall.step >= 2 and fall.time_in_step > 0.0
    fall_stamp = fall.header.stamp.sec + 1e-9 * fall.header.stamp.nanosec
    push_stamp = push.header.stamp.sec + 1e-9 * push.header.stamp.nanosec
    print(f"\npush of {magnitude:.3f} N s in step 2: fell in step {fall.step}, {fall.time_in_step:.3f} s into it, "
          f"{fall_stamp - push_stamp:.3f} s after the push: {fall.message}")


def test_a_ramp_of_cmd_vel_is_walked_at_the_commanded_speed(planner_node, tmp_path):
    """At real time: 1.0 m/s (the plan's speed), a ramp to 0.8 m/s over 2 s, then held: the mean
    speed of the pelvis (/odom) over four whole steps after the transitions is within 2 % of
    0.8 m/s, no fall; then 3 m/s is clamped to the rule's fastest speed, with a warning."""
    side = ClientSide("speed_test_client")
    odom: list[tuple[float, float]] = []
    events: list[GaitEvent] = []
    phases: list[GaitPhase] = []
    started: list[float] = []
    target = [1.0]

    def command() -> None:
        if started:
            elapsed = time.monotonic() - started[0]
            target[0] = 1.0 if elapsed < 1.0 else max(0.8, 1.0 - 0.1 * (elapsed - 1.0))
        side_pub.publish(Twist(linear=Vector3(x=target[0])))

    def stamp(header) -> float:
        return header.stamp.sec + 1e-9 * header.stamp.nanosec

    try:
        node = side.node
        side_pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(Odometry, "/odom", lambda m: odom.append((stamp(m.header), m.pose.pose.position.x)), 1000)
        node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        node.create_subscription(GaitPhase, "/gait_phase", phases.append, 100)
        node.create_subscription(JointState, "/joint_states", lambda m: None, 10)
        timer = node.create_timer(0.1, command)
        proc = simulator(tmp_path, "steps:=0", "real_time_factor:=1.0", "record:=false", "wait_for_subscribers:=1")
        side.wait(lambda: any(e.kind == GaitEvent.TOUCHDOWN for e in events), 60.0)
        started.append(time.monotonic())
        touchdowns = lambda: [e for e in events if e.kind == GaitEvent.TOUCHDOWN]  # noqa: E731
        side.wait(lambda: len(touchdowns()) >= 18 or any(e.kind == GaitEvent.FALL for e in events), 60.0)
        target_after = target[0]
        timer.cancel()
        side_pub.publish(Twist(linear=Vector3(x=3.0)))
        settle = time.monotonic() + 1.5
        side.wait(lambda: time.monotonic() > settle, 10.0)
        assert stop_node(proc) == 0
    finally:
        side.close()
    assert not [e for e in events if e.kind == GaitEvent.FALL]
    assert target_after == 0.8
    times = [stamp(e.header) for e in touchdowns()]
    stamps, xs = np.array([s for s, _ in odom]), np.array([x for _, x in odom])

    def x_at(t: float) -> float:
        return float(xs[np.argmin(np.abs(stamps - t))])

    speeds = [(x_at(b) - x_at(a)) / (b - a) for a, b in zip(times, times[1:])]
    print("\nspeed per step from /odom (m/s): " + " ".join(f"{v:.3f}" for v in speeds))
    mean = (x_at(times[17]) - x_at(times[13])) / (times[17] - times[13])
    print(f"mean speed over steps 14-17: {mean:.4f} m/s (command 0.8 m/s)")
    assert mean == pytest.approx(0.8, rel=0.02)
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert "speed command 3 m/s, 0 rad/s is outside the envelope (linear.x in [" in log and "clamped to" in log
    # The phases: a single support per step (right foot on even steps), a double support at each
    # touchdown, from the first single support received on.
    first = next(k for k, p in enumerate(phases) if p.phase != GaitPhase.DOUBLE_STANCE)
    sequence = [(p.phase, p.step) for p in phases[first:]]
    step = sequence[0][1]
    stance = lambda k: GaitPhase.RIGHT_STANCE if k % 2 == 0 else GaitPhase.LEFT_STANCE  # noqa: E731
    expected = [pair for k in range(step, step + len(sequence)) for pair in ((stance(k), k), (GaitPhase.DOUBLE_STANCE, k))]
    assert len(sequence) > 30 and sequence == expected[:len(sequence)]
