"""The simulator node standing (its default ``initial_state``, standing) over Fast DDS with a planner of its
own: the robot stands at rest (the pelvis still on /odom, /gait_phase STANDING, learnt by a
subscriber that joins late, /joint_states' efforts the balance controller's torques), a /cmd_vel to
walk is refused once with the core's physical reason and the robot stands on, a push within the
measured limit through ~/push is recovered, and the recording, read back by rosbags, holds what
was published; a push well above the limit is a fall with its reason. MuJoCo (``engine:=mujoco``)
stands on its contacts likewise."""

from __future__ import annotations

import time

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import numpy as np
from geometry_msgs.msg import Twist, Vector3
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from biped_gait.core.dynamics.closed_chain import ClosedChain
from biped_gait.core.dynamics.hybrid import HybridStep
from biped_gait.core.model.biped import BipedModel
from biped_gait.core.model.params import load_params
from biped_gait.core.model.urdf import UrdfJoints
from biped_gait.core.walking.balance import standing_pose
from biped_gait.ros.client import ClientSide
from biped_gait.ros.qos import LATCHED
from biped_gait_interfaces.msg import GaitEvent, GaitPhase
from biped_gait_interfaces.srv import Push

from .ros_helpers import planner_process, read_bag, start_simulator, stop_node

pytestmark = pytest.mark.ros

PLANNER = "standing_test_planner"
SIMULATOR = "biped_gait_simulator"
AT_REST = 1e-3  # m/s: the pelvis speed of a robot standing at rest
STILL_FOR = 2.0  # s of simulated time standing still before the push
PUSH = 0.5  # N s forward: within the measured limit (about 1 N s forward or back, 2 N s sideways)
DURATION = 8.0  # s standing: the push at about 2 s, recovered well before the end
NO_START_KEPT = 0.4  # rad: an arm amplitude the package keeps no start for (its start is the default gait's)


@pytest.fixture(scope="module")
def planner_node(tmp_path_factory):
    with planner_process(PLANNER, tmp_path_factory.mktemp("standing_planner")) as proc:
        yield proc


def _seconds(header) -> float:
    return header.stamp.sec + 1e-9 * header.stamp.nanosec


def _speed(msg: Odometry) -> float:
    v = msg.twist.twist.linear
    return float(np.linalg.norm([v.x, v.y, v.z]))


def _static_efforts() -> dict[str, float]:
    """The default set's standing posture's static torques (N m) by URDF joint, the back foot (the
    right) the stance foot."""
    bm = BipedModel.from_params(load_params(None))
    chain = ClosedChain(bm, HybridStep(bm).exchange)
    torque = np.zeros(bm.nq)
    torque[chain.actuated] = standing_pose(chain).torque
    joints = UrdfJoints(bm.params.joints, bm.coordinates)
    return dict(zip(joints.names, joints.array(torque, "right").tolist()))


def test_standing_at_rest_refusing_to_walk_and_recovering_from_a_push(planner_node, tmp_path):
    """Stands 2 s at rest under a /cmd_vel of 0.8 m/s from 0.5 s on, refused (once, with the
    reason: a gait the package keeps no start of), then a push of 0.5 N s, recovered by the end (8 s); a subscriber to /gait_phase that
    joins after 2 s receives STANDING (transient local); /joint_states' efforts are the standing
    posture's static torques; the recording holds the topics and the phase."""
    side = ClientSide("standing_test_client")
    odom: list[Odometry] = []
    events: list[GaitEvent] = []
    phases: list[GaitPhase] = []
    late: list[GaitPhase] = []
    joint_states: list[JointState] = []
    log_file = tmp_path / "biped-gait-simulator.log"
    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(Odometry, "/odom", odom.append, 1000)
        node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        node.create_subscription(GaitPhase, "/gait_phase", phases.append, 100)
        node.create_subscription(JointState, "/joint_states", joint_states.append, 1000)  # the walk waits for it
        client = node.create_client(Push, f"/{SIMULATOR}/push")
        proc = start_simulator(tmp_path, PLANNER, f"stand_duration:={DURATION}",
                               "real_time_factor:=1.0", "publish_rate:=100.0", "exit_when_done:=true",
                               "wait_for_subscribers:=1", f"arm_amplitude:={NO_START_KEPT}", initial_state=None)
        side.connect(client, 60.0)
        side.wait(lambda: odom and _seconds(odom[-1].header) - _seconds(odom[0].header) >= 0.5, 60.0)
        timer = node.create_timer(0.1, lambda: pub.publish(Twist(linear=Vector3(x=0.8))))
        side.wait(lambda: _seconds(odom[-1].header) - _seconds(odom[0].header) >= STILL_FOR, 60.0)
        still, resting = list(odom), list(joint_states)
        node.create_subscription(GaitPhase, "/gait_phase", late.append, LATCHED)  # joins 2 s after the phase began
        side.wait(lambda: late, 10.0)
        response = side.call(client, Push.Request(impulse=Vector3(x=PUSH), phase=0.0))
        assert response.success, response.message
        side.wait(lambda: "refused while standing" in log_file.read_text(), 60.0)  # the start planned: a second or two
        timer.cancel()
        side.wait(lambda: any(e.kind in (GaitEvent.FINISHED, GaitEvent.FALL) for e in events), 60.0)
        assert proc.wait(timeout=30) == 0
    finally:
        side.close()
    log = log_file.read_text()
    refusal = next(line for line in log.splitlines() if "refused while standing" in line)
    print(f"\n{refusal}")
    assert log.count("refused while standing") == 1 and "standing on" in refusal
    assert "cannot start from standing onto the gait L = 0.450 m, T = 0.450 s: the start step from theta_s" in refusal
    # At rest for 2 s, commanded to walk: the pelvis still, one phase, STANDING.
    speeds = [_speed(m) for m in still]
    print(f"pelvis speed standing over {_seconds(still[-1].header) - _seconds(still[0].header):.2f} s: "
          f"max {max(speeds):.1e} m/s")
    assert max(speeds) < AT_REST
    assert [(p.phase, p.step) for p in phases] == [(GaitPhase.STANDING, 0)]
    assert [(p.phase, p.step) for p in late] == [(GaitPhase.STANDING, 0)]
    # The torques that hold it: the posture's static torques at rest (the gain times 1e-9 rad of
    # rest, well below 1e-5 N m), not zero.
    static = _static_efforts()
    print("efforts standing: " + ", ".join(f"{name} {value:.3f}" for name, value in static.items()) + " N m")
    assert max(abs(v) for v in static.values()) > 0.5  # about 1 N m at the knees
    for msg in resting:
        assert dict(zip(msg.name, msg.effort)) == pytest.approx(static, abs=1e-5)
    # The push, recovered: no fall, the pelvis back where it stood and at rest by the end.
    [push] = [e for e in events if e.kind == GaitEvent.PUSH]
    assert not [e for e in events if e.kind == GaitEvent.FALL] and events[-1].kind == GaitEvent.FINISHED
    pushed = [m for m in odom if _seconds(m.header) > _seconds(push.header)]
    position = lambda m: np.array([m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z])  # noqa: E731
    moved = max(float(np.linalg.norm(position(m) - position(still[-1]))) for m in pushed)
    settled = float(np.linalg.norm(position(odom[-1]) - position(still[-1])))
    print(f"push of {PUSH} N s: the pelvis moved up to {moved * 1e3:.1f} mm, back within {settled * 1e3:.2f} mm, "
          f"at {_speed(odom[-1]):.1e} m/s {_seconds(odom[-1].header) - _seconds(push.header):.2f} s after it")
    assert max(_speed(m) for m in pushed) > 10 * AT_REST  # it did push
    assert settled < 5e-3 and _speed(odom[-1]) < 1e-2
    # The recording, read back by rosbags: what was published, the TF tree up to world.
    [bag] = list((tmp_path / "bags").iterdir())
    recorded = read_bag(bag)
    for topic in ("/joint_states", "/odom", "/tf", "/tf_static", "/angular_momentum", "/gait_phase", "/gait_events",
                  "/robot_description", "/diagnostics"):
        assert recorded.get(topic), topic
    assert [m.phase for _, m in recorded["/gait_phase"]] == [GaitPhase.STANDING]
    assert [m.kind for _, m in recorded["/gait_events"]] == [GaitEvent.PUSH, GaitEvent.FINISHED]
    statics = {(t.header.frame_id, t.child_frame_id) for _, m in recorded["/tf_static"] for t in m.transforms}
    moving = {(t.header.frame_id, t.child_frame_id) for _, m in recorded["/tf"][:1] for t in m.transforms}
    assert ("world", "odom") in statics and ("odom", "base_link") in moving
    states = [kv.value for _, m in recorded["/diagnostics"] for s in m.status for kv in s.values if kv.key == "state"]
    assert "standing" in states
    assert len(recorded["/odom"]) >= 100 * DURATION * 0.99


def test_mujoco_stands_on_its_contacts_and_recovers_a_push(planner_node, tmp_path):
    """``engine:=mujoco``: both feet on MuJoCo's floor, held by its contacts with friction; at rest
    before a scripted push of 0.5 N s (forward, at 0.225 s), at rest again by the end (4 s)."""
    proc = start_simulator(tmp_path, PLANNER, "engine:=mujoco", "stand_duration:=4.0",
                           "real_time_factor:=0.0", "publish_rate:=100.0", "exit_when_done:=true",
                           f"pushes:=0 0.5 {PUSH} 0 0", initial_state=None)
    assert proc.wait(timeout=120) == 0, (tmp_path / "biped-gait-simulator.log").read_text()
    [bag] = list((tmp_path / "bags").iterdir())
    recorded = read_bag(bag)
    assert [m.kind for _, m in recorded["/gait_events"]] == [GaitEvent.PUSH, GaitEvent.FINISHED]
    assert [m.phase for _, m in recorded["/gait_phase"]] == [GaitPhase.STANDING]
    odom = [m for _, m in recorded["/odom"]]
    before = [m for m in odom if _seconds(m.header) - _seconds(odom[0].header) < 0.2]
    assert before and max(_speed(m) for m in before) < AT_REST
    assert max(_speed(m) for m in odom) > 10 * AT_REST  # it did push
    assert _speed(odom[-1]) < AT_REST


@pytest.mark.parametrize("engine, reasons", [("hybrid", ("slips", "not positive")), ("mujoco", ("slid", "lifted"))])
def test_a_push_well_above_the_limit_is_a_fall_with_its_reason(planner_node, tmp_path, engine, reasons):
    """5 N s forward, scripted half a period into the standing: a FALL event with its reason (the
    planner's model: a foot's reaction leaves the cone; MuJoCo: a foot slides or lifts), the log
    line, exit status 1."""
    proc = start_simulator(tmp_path, PLANNER, f"engine:={engine}", "stand_duration:=2.0",
                           "real_time_factor:=0.0", "publish_rate:=100.0", "exit_when_done:=true",
                           "pushes:=0 0.5 5.0 0 0", initial_state=None)
    assert proc.wait(timeout=120) == 1
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert "the robot fell in step 0" in log
    [bag] = list((tmp_path / "bags").iterdir())
    events = [m for _, m in read_bag(bag)["/gait_events"]]
    assert [e.kind for e in events] == [GaitEvent.PUSH, GaitEvent.FALL]
    print(f"\npush of 5 N s standing ({engine}): {events[-1].message}")
    assert any(reason in events[-1].message for reason in reasons)
    assert events[0].time_in_step == pytest.approx(0.5 * 0.45, abs=1e-9)


def test_after_a_fall_its_message_is_the_last(planner_node, tmp_path):
    """Standing for a gait the package keeps no start of, a /cmd_vel to walk starts the planning of
    the start (a second or more, in a thread), and a push of 5 N s through ~/push makes the robot fall meanwhile: the fall's line is
    the walk's last warning or error (the refusal, if it was not said before the fall, is not said
    after it), and later commands are not answered."""
    side = ClientSide("fall_test_client")
    events: list[GaitEvent] = []
    log_file = tmp_path / "biped-gait-simulator.log"
    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        joint_states: list[JointState] = []
        node.create_subscription(JointState, "/joint_states", joint_states.append, 1000)
        client = node.create_client(Push, f"/{SIMULATOR}/push")
        proc = start_simulator(tmp_path, PLANNER, "stand_duration:=0.0",
                               "real_time_factor:=1.0", "publish_rate:=100.0", "record:=false",
                               "wait_for_subscribers:=1", "exit_when_done:=false", f"arm_amplitude:={NO_START_KEPT}",
                               initial_state=None)
        side.connect(client, 60.0)
        side.wait(lambda: joint_states, 60.0)  # it stands
        timer = node.create_timer(0.1, lambda: pub.publish(Twist(linear=Vector3(x=0.8))))
        started = time.monotonic()
        side.wait(lambda: time.monotonic() > started + 0.3)
        response = side.call(client, Push.Request(impulse=Vector3(x=5.0), phase=0.0))
        assert response.success, response.message
        side.wait(lambda: any(e.kind == GaitEvent.FALL for e in events), 60.0)
        fell = time.monotonic()
        side.wait(lambda: time.monotonic() > fell + 5.0)  # the start's planning done meanwhile, commands still coming
        timer.cancel()
        assert stop_node(proc) == 1  # the walk fell
    finally:
        side.close()
    lines = [line for line in log_file.read_text().splitlines() if "[WARN]" in line or "[ERROR]" in line]
    fell = next(k for k, line in enumerate(lines) if "the robot fell in step 0" in line)
    print("\n" + "\n".join(lines))
    assert fell == len(lines) - 1, lines[fell:]
