"""The simulator walks a double support that lasts (docs/model.md section 14.1) over Fast DDS, with
a planner of its own: -p double_support:=0.1 plans it (the planner's IPOPT solve) and walks 20 steps
in the hybrid engine, each double support on /gait_phase for its 0.1 s, the planned torques and the
feedback's on /joint_states' efforts in it (none in the ballistic single support); MuJoCo is
refused with its reason, exit status 2."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

from biped_gait_interfaces.msg import GaitEvent, GaitPhase

from .ros_helpers import planner_process, read_bag, start_simulator

pytestmark = pytest.mark.ros

PLANNER = "lasting_test_planner"
DURATION = 0.1  # s
STEPS = 20


def test_the_simulator_walks_a_double_support_that_lasts(tmp_path):
    """20 steps, no fall, exit status 0; every step's double support on /gait_phase from its first
    sample to the next single support, d to within a sample (publish_rate 500 Hz)."""
    with planner_process(PLANNER, tmp_path):
        proc = start_simulator(tmp_path, PLANNER, f"double_support:={DURATION}", f"steps:={STEPS}",
                               "real_time_factor:=0.0", "exit_when_done:=true")
        assert proc.wait(timeout=600) == 0, (tmp_path / "biped-gait-simulator.log").read_text()[-2000:]
    [bag] = list((tmp_path / "bags").iterdir())
    recorded = read_bag(bag)
    events = [m for _, m in recorded["/gait_events"]]
    assert not [e for e in events if e.kind == GaitEvent.FALL]
    assert len([e for e in events if e.kind == GaitEvent.TOUCHDOWN]) == STEPS
    phases = [m for _, m in recorded["/gait_phase"]]
    stamp = lambda m: m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec  # noqa: E731
    lasted = [stamp(after) - stamp(ds) for ds, after in zip(phases, phases[1:]) if ds.phase == GaitPhase.DOUBLE_STANCE]
    assert len(lasted) >= STEPS - 1
    assert all(abs(d - DURATION) <= 2 / 500 + 1e-9 for d in lasted), lasted
    # The joints' efforts: within the joint table's 200 N m, working in the double supports only.
    spans = [(stamp(ds), stamp(after)) for ds, after in zip(phases, phases[1:]) if ds.phase == GaitPhase.DOUBLE_STANCE]
    inside, outside = [], []
    for _, joints in recorded["/joint_states"]:
        t = stamp(joints)
        (inside if any(a < t < b for a, b in spans) else outside).append(max(abs(e) for e in joints.effort))
    assert inside and 10.0 < max(inside) <= 200.0 + 1e-9
    assert max(outside) <= 200.0 + 1e-9 and sorted(outside)[len(outside) // 2] == 0.0  # mostly ballistic


def test_mujoco_is_refused_with_its_reason(tmp_path):
    """-p double_support:=0.1 with engine:=mujoco: one line saying why, exit status 2."""
    proc = start_simulator(tmp_path, PLANNER, f"double_support:={DURATION}", "engine:=mujoco")
    assert proc.wait(timeout=60) == 2
    log = (tmp_path / "biped-gait-simulator.log").read_text()
    assert "needs engine 'hybrid'" in log
