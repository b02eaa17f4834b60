"""The simulator node over Fast DDS with a planner of its own: a 20-step walk that lands every
step on the plan, the topics an independent subscriber sees, the recording (read back by two
independent readers), SIGTERM and SIGKILL during a recording, a fall reported as such, and the
walk in MuJoCo (engine:=mujoco)."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import math
import re
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
from mcap_ros2.reader import read_ros2_messages
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from biped_gait.cli import main as cli_main
from biped_gait.recording.recover import is_complete
from biped_gait.core.model.params import load_params
from biped_gait.core.walking.steering import DEFAULT_RATE
from biped_gait.core.walking.events import Touchdown
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.walk import Walk
from biped_gait.ros.client import ClientSide
from biped_gait_interfaces.msg import AngularMomentum, GaitEvent

from .ros_helpers import read_bag, planner_process, start_simulator, stop_node

PHYSICAL_JOINTS = load_params().joints.physical_names()  # the default set's URDF joints

pytestmark = pytest.mark.ros

PLANNER = "sim_test_planner"


@pytest.fixture(scope="module")
def planner_node(tmp_path_factory):
    with planner_process(PLANNER, tmp_path_factory.mktemp("sim_planner")) as proc:
        yield proc


def simulator(where: Path, *params: str) -> subprocess.Popen:
    return start_simulator(where, PLANNER, *params)


@pytest.fixture(scope="module")
def twenty_steps(planner_node, tmp_path_factory):
    """A 20-step walk, as fast as possible, recorded; the process exits by itself."""
    where = tmp_path_factory.mktemp("walk20")
    proc = simulator(where, "steps:=20", "real_time_factor:=0.0", "exit_when_done:=true")
    assert proc.wait(timeout=300) == 0, (where / "biped-gait-simulator.log").read_text()
    [bag] = list((where / "bags").iterdir())
    return bag


def test_twenty_steps_land_on_the_plan(twenty_steps):
    topics = read_bag(twenty_steps)
    events = [m for _, m in topics["/gait_events"]]
    touchdowns = [e for e in events if e.kind == GaitEvent.TOUCHDOWN]
    assert len(touchdowns) == 20 and events[-1].kind == GaitEvent.FINISHED
    assert not [e for e in events if e.kind == GaitEvent.FALL]
    drift = [e.state_error for e in touchdowns]
    print("\nstate error at each touchdown (rad, rad/s):", " ".join(f"{d:.1e}" for d in drift))
    assert max(drift) < 1e-9  # stated tolerance
    assert [e.step for e in touchdowns] == list(range(20))
    assert [e.stance_side for e in touchdowns[:2]] == ["left", "right"]  # the side that starts next
    assert all(abs(e.time_in_step - 0.45) < 1e-9 for e in touchdowns)
    assert np.allclose([e.effort_cost for e in touchdowns], touchdowns[0].effort_cost, rtol=1e-7)


def test_the_recording_holds_what_was_published(twenty_steps):
    [mcap_path] = list(twenty_steps.glob("*.mcap"))
    assert is_complete(mcap_path)
    topics = read_bag(twenty_steps)
    counts = {t: len(v) for t, v in topics.items()}
    # Every instant k / 500 s before the last touchdown (at 9 s, to rounding: 4500 or 4501 instants).
    assert counts["/joint_states"] == counts["/odom"] == counts["/angular_momentum"] == counts["/tf"]
    assert counts["/joint_states"] in (20 * 225, 20 * 225 + 1)
    assert counts["/robot_description"] == counts["/tf_static"] == 1 and counts["/gait_events"] == 21
    stamps = np.array([s for s, _ in topics["/joint_states"]])
    assert np.allclose(np.diff(stamps), 2e6, atol=2)  # 500 Hz of simulated time, ns
    joint = topics["/joint_states"][100][1]
    assert list(joint.name) == list(PHYSICAL_JOINTS)
    tf = topics["/tf"][100][1]
    frames = {(t.header.frame_id, t.child_frame_id) for t in tf.transforms}
    assert ("odom", "base_link") in frames and ("base_link", "torso") in frames and len(frames) == 8
    assert "<robot" in topics["/robot_description"][0][1].data
    # The stance foot moves forward by L each step and alternates sides.
    feet = {m.step: (m.stance_foot.x, m.stance_foot.y, m.stance_side) for _, m in topics["/angular_momentum"]}
    for step, (x, y, side) in feet.items():
        assert x == pytest.approx(0.45 * step, abs=1e-9)
        assert side == ("right" if step % 2 == 0 else "left")
        assert y == pytest.approx(-0.2 if side == "right" else 0.2, abs=1e-9)
    # mcap-ros2-support decodes the same file, custom and hand-written (/tf) schemas included.
    decoded = {}
    for m in read_ros2_messages(str(mcap_path)):
        decoded[m.channel.topic] = decoded.get(m.channel.topic, 0) + 1
    assert decoded == counts


@pytest.mark.paced
def test_an_independent_subscriber_sees_the_topics(planner_node, tmp_path):
    """Real time (factor 1), two steps: names, frames, the 500 Hz of the stamps, and the walk no
    faster than the wall clock by the node's own measure (a pacer that ran ahead would be; a
    loaded machine makes samples late and then publishes them at once, so their arrivals' rate
    is not the pacing's)."""
    side = ClientSide("sim_topic_listener")
    got: dict[str, list] = {"joints": [], "odom": [], "momentum": [], "events": []}
    try:
        side.node.create_subscription(JointState, "/joint_states", lambda m: got["joints"].append(m), 1000)
        side.node.create_subscription(Odometry, "/odom", lambda m: got["odom"].append(m), 1000)
        side.node.create_subscription(AngularMomentum, "/angular_momentum", lambda m: got["momentum"].append(m), 1000)
        side.node.create_subscription(GaitEvent, "/gait_events", lambda m: got["events"].append(m), 100)
        proc = simulator(tmp_path, "steps:=2", "real_time_factor:=1.0", "exit_when_done:=true", "record:=false",
                         "wait_for_subscribers:=1")
        side.wait(lambda: any(e.kind == GaitEvent.FINISHED for e in got["events"]) or proc.poll() is not None, 120.0)
        deadline = time.monotonic() + 1.0
        side.wait(lambda: time.monotonic() > deadline, 5.0)  # let the last samples arrive
        assert proc.wait(timeout=30) == 0
    finally:
        side.close()
    joints = got["joints"]
    assert len(joints) >= 0.9 * 450, len(joints)  # 2 steps x 225 samples; a few may be late
    assert list(joints[0].name) == list(PHYSICAL_JOINTS) and len(joints[0].velocity) == 7
    stamps = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in joints])
    assert np.diff(stamps) == pytest.approx(2e6, abs=1e3)  # ns: 500 Hz of simulated time
    [factor] = re.findall(r"real-time factor ([0-9.]+)\)", (tmp_path / "biped-gait-simulator.log").read_text())
    print(f"\n/joint_states: {len(joints)} messages; the walk at real-time factor {factor}")
    assert float(factor) <= 1.01  # to the log's two decimals
    odom = got["odom"][-1]
    assert odom.header.frame_id == "odom" and odom.child_frame_id == "base_link"
    assert 0.8 < odom.pose.pose.position.z < 0.95  # the pelvis stays about a leg length up
    momentum = got["momentum"][-1]
    assert momentum.header.frame_id == "world" and momentum.stance_side in ("left", "right")
    kinds = [e.kind for e in got["events"]]
    assert kinds == [GaitEvent.TOUCHDOWN, GaitEvent.TOUCHDOWN, GaitEvent.FINISHED]


def test_sigterm_leaves_a_complete_recording(planner_node, tmp_path):
    proc = simulator(tmp_path, "steps:=0", "real_time_factor:=1.0")
    side = ClientSide("sim_sigterm_listener")
    samples = []
    try:  # stopped once 150 samples were published (0.3 s of walk), however loaded the machine
        side.node.create_subscription(JointState, "/joint_states", samples.append, 1000)
        side.wait(lambda: len(samples) >= 150 or proc.poll() is not None, 120.0)
    finally:
        side.close()
    assert len(samples) >= 150
    assert stop_node(proc, signal.SIGTERM) == 0
    [bag] = list((tmp_path / "bags").iterdir())
    [mcap_path] = list(bag.glob("*.mcap"))
    assert is_complete(mcap_path) and (bag / "metadata.yaml").is_file()
    assert len(read_bag(bag)["/joint_states"]) > 100


def test_sigkill_loses_at_most_the_last_chunk(planner_node, tmp_path):
    side = ClientSide("sim_kill_listener")
    stamps: list[int] = []
    try:
        side.node.create_subscription(
            JointState, "/joint_states",
            lambda m: stamps.append(m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec), 1000)
        proc = simulator(tmp_path, "steps:=0", "real_time_factor:=1.0", "chunk_size:=16384", "wait_for_subscribers:=1")
        side.wait(lambda: len(stamps) > 600, 120.0)
        proc.kill()
        proc.wait()
    finally:
        side.close()
    [bag] = list((tmp_path / "bags").iterdir())
    [mcap_path] = list(bag.glob("*.mcap"))
    assert not is_complete(mcap_path)
    assert cli_main(["recover", str(bag)]) == 0
    recovered = bag.parent / (bag.name + "_recovered")
    joints = read_bag(recovered)["/joint_states"]
    got = np.array([s for s, _ in joints])
    # From the start (the live subscriber may join late), in order, no gap.
    assert np.all(np.diff(got) > 0) and got[0] <= stamps[0]
    assert np.allclose(np.diff(got), 2e6, atol=2)
    # Lost: what was published after the last complete chunk. A 16 KiB chunk holds a few
    # tens of samples of the four sampled topics, so the loss is bounded by one chunk's worth.
    size = next(recovered.glob("*.mcap")).stat().st_size
    per_sample = size / len(joints)
    lost = sum(1 for s in stamps if s > got[-1])
    print(f"\nSIGKILL: {len(joints)} samples recovered, {lost} published after the last complete chunk "
          f"(one chunk ~ {16384 / per_sample:.0f} samples)")
    assert lost <= 2 * 16384 / per_sample + 5


def test_a_fall_is_detected_and_reported(planner_node, tmp_path):
    """Without re-aiming the gait is open-loop unstable: it falls within a few steps, and the
    simulator says so on /gait_events, in its log and its exit status, and stops walking."""
    proc = simulator(tmp_path, "steps:=20", "real_time_factor:=0.0", "exit_when_done:=true", "reaim:=false")
    assert proc.wait(timeout=300) == 1
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert "the robot fell in step" in log
    [bag] = list((tmp_path / "bags").iterdir())
    events = [m for _, m in read_bag(bag)["/gait_events"]]
    assert events[-1].kind == GaitEvent.FALL and events[-1].message
    touchdowns = [e for e in events if e.kind == GaitEvent.TOUCHDOWN]
    assert len(touchdowns) < 20 and all(e.step < events[-1].step for e in touchdowns)


def test_the_hips_model_walks_and_publishes_its_hip_joints(planner_node, tmp_path):
    """aoustin2013-hips through the nodes: the planner's 13-DOF gait walked 3 steps; /joint_states
    and /tf carry the hips' joints, the events the eleven impulses with their joints' names."""
    proc = simulator(tmp_path, "steps:=3", "real_time_factor:=0.0", "exit_when_done:=true",
                     "params:=aoustin2013-hips", f"arm_amplitude:={math.radians(20.0)}")
    assert proc.wait(timeout=300) == 0, (tmp_path / "biped-gait-simulator.log").read_text()
    [bag] = list((tmp_path / "bags").iterdir())
    topics = read_bag(bag)
    names = list(load_params("aoustin2013-hips").joints.physical_names())
    joint = topics["/joint_states"][50][1]
    assert list(joint.name) == names and len(joint.position) == 11
    touchdowns = [m for _, m in topics["/gait_events"] if m.kind == GaitEvent.TOUCHDOWN]
    assert len(touchdowns) == 3 and max(e.state_error for e in touchdowns) < 1e-9
    assert len(touchdowns[0].i_minus) == len(touchdowns[0].joint_names) == 11
    assert "stance_hip_roll" in touchdowns[0].joint_names
    frames = {t.child_frame_id for t in topics["/tf"][50][1].transforms}
    assert {"right_hip_yaw_link", "right_hip_roll_link", "left_thigh"} <= frames
    rolls = np.array([m.position[names.index("left_hip_roll")] for _, m in topics["/joint_states"]])
    assert np.abs(rolls).max() > math.radians(3.0)  # the hips move


def test_the_mujoco_engine_walks_and_records(planner_node, tmp_path, default_gait):
    """engine:=mujoco through the nodes: 3 steps of the default gait with 5 ms pulses at 1 kHz,
    recorded; the events carry what the pulses applied and land where the core's MuJoCo walk of
    the same plan lands (the node only publishes it), /joint_states every millisecond."""
    proc = simulator(tmp_path, "steps:=3", "real_time_factor:=0.0", "exit_when_done:=true", "engine:=mujoco",
                     "pulse_duration:=0.005", "publish_rate:=1000.0")
    assert proc.wait(timeout=300) == 0, (tmp_path / "biped-gait-simulator.log").read_text()
    assert "engine mujoco (double support of 5 ms)" in (tmp_path / "biped-gait-simulator.log").read_text()
    [bag] = list((tmp_path / "bags").iterdir())
    topics = read_bag(bag)
    events = [m for _, m in topics["/gait_events"]]
    touchdowns = [e for e in events if e.kind == GaitEvent.TOUCHDOWN]
    assert len(touchdowns) == 3 and events[-1].kind == GaitEvent.FINISHED
    core = Walk(PlannedOrbit.of(default_gait), 1000.0, 3, engine="mujoco", pulse_duration=0.005,
                momentum_rate=DEFAULT_RATE)
    expected = [item for item in core if isinstance(item, Touchdown)]
    for event, td in zip(touchdowns, expected):
        assert abs(event.time_in_step - td.t_step) < 1e-6
        assert np.allclose(event.i_minus, td.i_minus, atol=1e-6) and np.allclose(event.i_plus, td.i_plus, atol=1e-6)
        assert event.effort_cost == pytest.approx(td.W, rel=1e-6)
        assert event.effort_cost == pytest.approx(default_gait.W, rel=0.1)  # the pulses' effort, near the impulses'
    assert touchdowns[0].state_error < 1e-7  # started on the plan: MuJoCo's first step is the plan's
    assert abs(len(topics["/joint_states"]) - 1000 * expected[-1].t) <= 1
    assert len(topics["/joint_states"]) == len(topics["/odom"]) == len(topics["/tf"])
