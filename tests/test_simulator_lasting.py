"""The simulator walks a double support that lasts (docs/model.md section 14.1) over Fast DDS, with
a planner of its own: -p double_support:=0.1 plans it (the planner's IPOPT solve) and walks 20 steps
in the hybrid engine, for the paper's 9-joint biped and the 13-joint one with its hips, each double
support on /gait_phase for its 0.1 s, the planned torques and the feedback's on /joint_states'
efforts in it (none in the ballistic single support); MuJoCo is refused with its reason, exit
status 2."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

from .ros_helpers import double_supports, planner_process, stamp, start_simulator, walk_recorded

pytestmark = pytest.mark.ros

PLANNER = "lasting_test_planner"
DURATION = 0.1  # s
STEPS = 20


@pytest.mark.parametrize("params", ["aoustin2013", "aoustin2013-hips"])
def test_the_simulator_walks_a_double_support_that_lasts(tmp_path, params):
    """20 steps, no fall, exit status 0; every step's double support on /gait_phase from its first
    sample to the next single support, d to within a sample (publish_rate 500 Hz); for both
    parameter sets (with lateral hip joints the feet held in x, y, z and heading, the kinematic leg
    exchange at each lift-off; its cycle is tests/test_lasting_hips.py's, from the session's solve
    cache when that module solved it first)."""
    with planner_process(PLANNER, tmp_path):
        recorded = walk_recorded(tmp_path, PLANNER, STEPS, f"double_support:={DURATION}", f"params:={params}")
    spans = double_supports(recorded)
    assert len(spans) >= STEPS - 1
    assert all(abs(b - a - DURATION) <= 2 / 500 + 1e-9 for a, b in spans), spans
    # The joints' efforts: within the joint table's 200 N m, working in the double supports only.
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
