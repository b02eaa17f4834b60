"""The simulator node and stopping, over Fast DDS with a planner of its own: /cmd_vel linear.x 0
during a walk logs why the walk cannot stop (the core refuses the stop step, docs/model.md section
8.10) and walks on at the slowest gait, with no fall; so does no /cmd_vel for cmd_vel_timeout
after a command. (A start from standing: tests/test_simulator_standing.py.)"""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist, Vector3
from sensor_msgs.msg import JointState

from biped_gait.ros.client import ClientSide
from biped_gait.ros.qos import LATCHED
from biped_gait_interfaces.msg import GaitEvent, VelocityEnvelope

from .ros_helpers import planner_process, start_simulator, stop_node

pytestmark = pytest.mark.ros

PLANNER = "start_stop_test_planner"


@pytest.fixture(scope="module")
def planner_node(tmp_path_factory):
    with planner_process(PLANNER, tmp_path_factory.mktemp("start_stop_planner")) as proc:
        yield proc


def test_cmd_vel_zero_says_why_the_walk_cannot_stop(planner_node, tmp_path):
    """The reason is said of the gait that walks when it is said: the envelope's slowest, which
    the walk slows to (a straight gait), not the one walked when the command came."""
    side = ClientSide("start_stop_test_client")
    events: list[GaitEvent] = []
    envelopes: list[VelocityEnvelope] = []
    log_file = tmp_path / "biped-gait-simulator.log"
    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        node.create_subscription(JointState, "/joint_states", lambda m: None, 10)
        node.create_subscription(VelocityEnvelope, "/biped_gait_simulator/velocity_envelope", envelopes.append, LATCHED)
        proc = start_simulator(tmp_path, PLANNER, "steps:=0", "real_time_factor:=1.0", "record:=false",
                               "wait_for_subscribers:=1")
        side.wait(lambda: any(e.kind == GaitEvent.TOUCHDOWN for e in events) and envelopes, 60.0)
        timer = node.create_timer(0.2, lambda: pub.publish(Twist(linear=Vector3(x=0.0))))
        side.wait(lambda: log_file.exists() and "cannot stop from the gait" in log_file.read_text(), 60.0)
        timer.cancel()
        count = len([e for e in events if e.kind == GaitEvent.TOUCHDOWN])
        side.wait(lambda: len([e for e in events if e.kind == GaitEvent.TOUCHDOWN]) >= count + 3, 30.0)
        assert stop_node(proc) == 0
    finally:
        side.close()
    log = log_file.read_text()
    said = next(line for line in log.splitlines() if "cannot stop" in line)
    print("\n" + said)
    length, period = (float(said.split(f"{name} = ")[1].split(" ")[0]) for name in ("L", "T"))
    # the slowest gait's speed, from L and T as logged (3 decimals: within 2e-3 m/s)
    assert length / period == pytest.approx(envelopes[0].min_linear_x, abs=2e-3)
    assert "no step found beyond" in log and "the legs' reach 1.814 m" in log and "walking on at the slowest gait" in log
    assert "clamped to" in log  # 0 m/s is below the envelope, walked as its slowest speed
    assert not [e for e in events if e.kind == GaitEvent.FALL]


def test_no_cmd_vel_for_the_timeout_is_a_command_of_0(planner_node, tmp_path):
    """/cmd_vel 0.8 m/s every 0.1 s, then none: within cmd_vel_timeout (0.5 s) and a step of
    simulated time the commanded speed (in /diagnostics) is the envelope's slowest, logged once,
    with no fall."""
    side = ClientSide("timeout_test_client")
    events: list[GaitEvent] = []
    commanded: list[str] = []
    envelopes: list[VelocityEnvelope] = []
    log_file = tmp_path / "biped-gait-simulator.log"

    def diagnostics(msg: DiagnosticArray) -> None:
        commanded.extend(kv.value for s in msg.status for kv in s.values if kv.key == "commanded speed (m/s)")

    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        node.create_subscription(DiagnosticArray, "/diagnostics", diagnostics, 10)
        node.create_subscription(VelocityEnvelope, "/biped_gait_simulator/velocity_envelope", envelopes.append, LATCHED)
        node.create_subscription(JointState, "/joint_states", lambda m: None, 10)
        proc = start_simulator(tmp_path, PLANNER, "steps:=0", "real_time_factor:=1.0", "record:=false",
                               "wait_for_subscribers:=1", "cmd_vel_timeout:=0.5")
        side.wait(lambda: any(e.kind == GaitEvent.TOUCHDOWN for e in events) and envelopes, 60.0)
        timer = node.create_timer(0.1, lambda: pub.publish(Twist(linear=Vector3(x=0.8))))
        side.wait(lambda: "0.8000" in commanded, 30.0)
        timer.cancel()
        slowest = f"{envelopes[0].min_linear_x:.4f}"
        side.wait(lambda: commanded[-1] == slowest, 30.0)
        side.wait(lambda: "walking on at the slowest gait" in log_file.read_text(), 60.0)
        assert stop_node(proc) == 0
    finally:
        side.close()
    log = log_file.read_text()
    lapses = [line for line in log.splitlines() if "no /cmd_vel for" in line]
    print("\n" + lapses[0] + f"\ncommanded speed after it: {commanded[-1]} m/s (the envelope's slowest)")
    assert len(lapses) == 1 and "taken as 0 m/s" in lapses[0]
    silent = float(lapses[0].split("no /cmd_vel for ")[1].split(" s")[0])
    assert 0.5 <= silent <= 0.5 + 0.6  # the timeout, and at most a step (the gaits' periods are below 0.6 s)
    assert not [e for e in events if e.kind == GaitEvent.FALL]
