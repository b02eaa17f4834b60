"""The simulator node and starting and stopping, over Fast DDS with a planner of its own: with
``start_from_rest`` the walk does not start and says why (the core refuses the start step,
docs/model.md section 8.10), exit status 1 and a NOT_STARTED event in the recording; /cmd_vel
linear.x 0 during a walk logs why the walk cannot stop and walks on at the slowest gait, with
no fall."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import time

from geometry_msgs.msg import Twist, Vector3
from sensor_msgs.msg import JointState

from biped_gait.ros.client import ClientSide
from biped_gait_interfaces.msg import GaitEvent

from .ros_helpers import planner_process, read_bag, start_simulator, stop_node

pytestmark = pytest.mark.ros

PLANNER = "start_stop_test_planner"


@pytest.fixture(scope="module")
def planner_node(tmp_path_factory):
    with planner_process(PLANNER, tmp_path_factory.mktemp("start_stop_planner")) as proc:
        yield proc


def test_start_from_rest_is_refused_with_its_reason(planner_node, tmp_path):
    proc = start_simulator(tmp_path, PLANNER, "start_from_rest:=true", "exit_when_done:=true", "steps:=4")
    assert proc.wait(timeout=120) == 1
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert "the walk did not start: cannot start from rest: the start step from theta_s = " in log
    assert "vertical ground reaction not positive" in log
    bags = list((tmp_path / "bags").iterdir())
    events = [m for _, m in read_bag(bags[0]).get("/gait_events", [])]
    assert [e.kind for e in events] == [GaitEvent.NOT_STARTED] and "cannot start from rest" in events[0].message


def test_cmd_vel_zero_says_why_the_walk_cannot_stop(planner_node, tmp_path):
    side = ClientSide("start_stop_test_client")
    events: list[GaitEvent] = []
    log_file = tmp_path / "biped-gait-simulator.log"
    try:
        node = side.node
        pub = node.create_publisher(Twist, "/cmd_vel", 10)
        node.create_subscription(GaitEvent, "/gait_events", events.append, 100)
        node.create_subscription(JointState, "/joint_states", lambda m: None, 10)
        proc = start_simulator(tmp_path, PLANNER, "steps:=0", "real_time_factor:=1.0", "record:=false",
                               "wait_for_subscribers:=1")
        side.wait(lambda: any(e.kind == GaitEvent.TOUCHDOWN for e in events), 60.0)
        timer = node.create_timer(0.2, lambda: pub.publish(Twist(linear=Vector3(x=0.0))))
        side.wait(lambda: log_file.exists() and "cannot stop from the gait" in log_file.read_text(), 60.0)
        timer.cancel()
        count = len([e for e in events if e.kind == GaitEvent.TOUCHDOWN])
        side.wait(lambda: len([e for e in events if e.kind == GaitEvent.TOUCHDOWN]) >= count + 3, 30.0)
        assert stop_node(proc) == 0
    finally:
        side.close()
    log = log_file.read_text()
    print("\n" + next(line for line in log.splitlines() if "cannot stop" in line))
    assert "no step found beyond" in log and "the legs' reach 1.814 m" in log and "walking on at the slowest gait" in log
    assert "clamped to" in log  # 0 m/s is below the envelope, walked as its slowest speed
    assert not [e for e in events if e.kind == GaitEvent.FALL]
