"""The swing actuated at its two ends through the ROS interfaces, over Fast DDS (docs/model.md
sections 15 and 15.1): the planner node answers PlanGait's actuated_swing with the cycle a walk
tracks (its swing_phases), refuses the values it cannot plan and serves on; the simulator with
-p actuated_swing:=0.1 -p double_support:=0.1 walks it in the hybrid engine, every joint's effort
within the joint table's 200 N m; MuJoCo, and an actuated swing without a double support that
lasts, refused at start with their reasons.

One IPOPT solve for the module: the walkable cycle at (tau, d) = (0.1, 0.1) s at the default gait
(about a minute on the project's 2-core machine; none when the session's disk cache has it from
tests/test_actuated_walk.py, core/gait/solve_cache.py), planned once by a planner of the module's
own; the simulator's request, the same, is answered from that planner's cache."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

from biped_gait_interfaces.srv import PlanGait  # noqa: E402

from biped_gait.ros.client import ClientSide, plan_request  # noqa: E402
from biped_gait.ros.conversions import swing_cycle_from_msg  # noqa: E402

from .ros_helpers import double_supports, planner_process, stamp, start_simulator, walk_recorded  # noqa: E402

pytestmark = pytest.mark.ros

PLANNER = "actuated_test_planner"
TAU = DURATION = 0.1  # s
LIMIT = 200.0  # N m, the joint table's effort
# IPOPT's tolerance on the torques' scale (as tests/test_planner_node.py): a torque at its limit may pass it by this much.
TORQUE_TOLERANCE = 1e-4  # N m
STEPS = 3


@pytest.fixture(scope="module")
def node_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("actuated")


@pytest.fixture(scope="module")
def ros(node_dir):
    with planner_process(PLANNER, node_dir):
        side = ClientSide("actuated_test_client")
        side.client = side.node.create_client(PlanGait, f"/{PLANNER}/plan_gait")
        side.connect(side.client)
        yield side
        side.close()


@pytest.fixture(scope="module")
def answered(ros):
    """The planner's answer to actuated_swing 0.1 s with double_support 0.1 s (the module's solve),
    and the wall time it took (s)."""
    started = time.monotonic()
    response = ros.call(ros.client, plan_request(actuated_swing=TAU, double_support=DURATION), timeout=600.0)
    return response, time.monotonic() - started


def test_the_planner_answers_the_swing_actuated_at_its_two_ends(ros, answered):
    """The walkable cycle (docs/model.md 15.1): each end 41 samples (20 intervals) over tau, in the
    plan's double_support_coordinates and actuated_joints; every torque of both ends and of the
    double support within 200 N m, the peak torque over the cycle theirs; no impulse (the double
    support's I^- and I^+ zero); E above the paper's W; again from the cache."""
    response, seconds = answered
    print(f"\nplan_gait with actuated_swing {TAU} s, double_support {DURATION} s answered in {seconds:.1f} s: "
          f"{response.message}")
    assert response.success, response.message
    plan = response.plan
    swing, phase = plan.swing_phases, plan.double_support_phase
    assert swing.success and swing.actuated_swing == TAU and "swing actuated for 0.1 s at each end" in response.message
    nx, na = len(plan.double_support_coordinates), len(plan.actuated_joints)
    torques = []
    for end, t0 in ((swing.start, 0.0), (swing.end, plan.period - TAU)):
        n = len(end.t)
        assert n == 41 and end.t[0] == pytest.approx(t0, abs=1e-12) and end.t[-1] == pytest.approx(t0 + TAU, abs=1e-12)
        for name, size in (("x", n * nx), ("xd", n * nx), ("xdd", n * nx), ("torques", n * na),
                           ("contact_forces", n * 3)):
            assert len(getattr(end, name)) == size, name
        assert np.reshape(end.contact_forces, (n, 3))[:, 2].min() > 0.0  # the stance tip presses
        torques.append(np.reshape(end.torques, (n, na)))
    torques.append(np.reshape(phase.torques, (len(phase.t), na)))
    peak = np.max([np.abs(t).max(axis=0) for t in torques], axis=0)
    assert peak.max() <= LIMIT + TORQUE_TOLERANCE and np.array_equal(peak, swing.peak_torque)
    assert phase.duration == DURATION and not np.any(phase.i_minus) and not np.any(phase.i_plus)
    assert swing.effort_total > plan.effort_cost and swing.iterations > 0 and swing.solve_time > 0.0
    print(f"E = {swing.effort_total:.3f} N m s, peak torques {np.round(swing.peak_torque, 1).tolist()} N m, "
          f"IPOPT {swing.iterations} iterations in {swing.solve_time:.1f} s")
    again = ros.call(ros.client, plan_request(actuated_swing=TAU, double_support=DURATION))
    assert again.message == response.message + " (cached)"
    assert list(again.plan.swing_phases.end.torques) == list(swing.end.torques)
    cycle = swing_cycle_from_msg(plan)
    assert np.array_equal(cycle.peak_torque, swing.peak_torque) and cycle.support.duration == DURATION


def test_bad_actuated_swings_are_refused_and_the_node_serves_on(ros, answered):
    """A duration that is none, not below half the period, or beside a stride on a circle: success
    false, one line, the next request answered."""
    for request, message in [
        (plan_request(actuated_swing=-0.1, double_support=DURATION), "actuated_swing must be a duration > 0 s"),
        (plan_request(actuated_swing=math.nan, double_support=DURATION), "actuated_swing must be a duration > 0 s"),
        (plan_request(actuated_swing=math.inf), "actuated_swing must be a duration > 0 s"),
        (plan_request(actuated_swing=0.225, double_support=DURATION), "below half the period (0.225 s)"),
        (plan_request(params="aoustin2013-hips", turn_radius=2.5, actuated_swing=TAU), "straight gaits only"),
    ]:
        response = ros.call(ros.client, request, timeout=120.0)
        assert not response.success and message in response.message, response.message
        assert "\n" not in response.message
    assert ros.call(ros.client, plan_request(arm_amplitude=0.3)).success


def test_the_simulator_walks_the_actuated_swing(ros, answered, tmp_path):
    """-p actuated_swing:=0.1 -p double_support:=0.1: the planner's cycle (from its cache) walked in
    the hybrid engine, STEPS steps without a fall, exit status 0; each double support on /gait_phase
    for its 0.1 s; /joint_states' efforts within 200 N m, at it in the actuated ends of the swing (the
    least-effort torques there are at the limit or near zero: measured 200 N m over the start's first
    45 ms, then below 3), none in the ballistic flight between."""
    assert answered[0].success, answered[0].message
    recorded = walk_recorded(tmp_path, PLANNER, STEPS, f"actuated_swing:={TAU}", f"double_support:={DURATION}")
    spans = double_supports(recorded)
    assert len(spans) >= STEPS - 1 and all(abs(b - a - DURATION) <= 2 / 500 + 1e-9 for a, b in spans), spans
    efforts = [(stamp(m), max(abs(e) for e in m.effort)) for _, m in recorded["/joint_states"]]
    # Each step from its lift-off: the actuated start (0 to tau), the flight, the actuated end (T - tau to T), then
    # the double support (T to T + d); 5 ms off each boundary.
    period = answered[0].plan.period
    in_step = lambda t: (t - efforts[0][0]) % (period + DURATION)  # noqa: E731
    ends = [e for t, e in efforts if 0.005 < in_step(t) < TAU - 0.005 or period - TAU + 0.005 < in_step(t) < period - 0.005]
    flight = [e for t, e in efforts if TAU + 0.005 < in_step(t) < period - TAU - 0.005]
    print(f"\n{len(efforts)} samples, the largest effort {max(e for _, e in efforts):.1f} N m")
    assert max(e for _, e in efforts) <= LIMIT + 1e-9
    assert max(ends) > 0.99 * LIMIT and flight and max(flight) == 0.0


def test_mujoco_and_a_swing_without_a_double_support_are_refused(tmp_path):
    """-p actuated_swing:=0.1 with engine:=mujoco, without double_support, or with the hip-joint
    biped (planned, not walked): one line saying why, exit status 2."""
    for params, reason in (((f"double_support:={DURATION}", "engine:=mujoco"), "needs engine 'hybrid': MuJoCo's floor"),
                           ((), "needs double_support > 0"),
                           ((f"double_support:={DURATION}", "params:=aoustin2013-hips"),
                            "with aoustin2013-hips: planned, not walked")):
        proc = start_simulator(tmp_path, PLANNER, f"actuated_swing:={TAU}", *params)
        assert proc.wait(timeout=60) == 2
        log = (tmp_path / "biped-gait-simulator.log").read_text()
        assert f"actuated_swing {TAU:g} s {reason}" in log, log
