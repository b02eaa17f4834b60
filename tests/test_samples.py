"""Many samples evaluated in one call: the compiled twin and the Python loops agree, and both
agree with the one-sample functions of the model; the world view of many instants is the world
view of each."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from biped_gait.core.gait.figures import step_figures
from biped_gait.core.dynamics.samples import JointPlacements, SampleEvaluator, ground_reaction_inverse_dynamics
from biped_gait.core.walking.world import WorldView

pytestmark = pytest.mark.core


@pytest.fixture(scope="module")
def states(default_gait):
    """The default gait's samples and states far from it (rad, rad/s), one per row."""
    rng = np.random.default_rng(4)
    samples = default_gait.figures.samples
    q = np.vstack([samples.q, rng.uniform(-1.5, 1.5, (15, 9))])
    qd = np.vstack([samples.qd, rng.uniform(-4.0, 4.0, (15, 9))])
    return q, qd


def _assert_same(a, b, scale_rtol=1e-13):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert np.max(np.abs(a - b)) <= scale_rtol * max(1.0, np.max(np.abs(b)))


def test_compiled_and_python_evaluations_agree(planner, states):
    """Same Pinocchio algorithms in both (the compiled twin built by tools/build_native.sh):
    every array equal to rounding."""
    compiled = SampleEvaluator(planner.model, native=True)
    python = SampleEvaluator(planner.model, native=False)
    q, qd = states
    a, b = compiled.dynamics(q, qd), python.dynamics(q, qd)
    for name in ("qdd", "grf", "swing_height", "yaw_momentum", "lowest_link"):
        _assert_same(getattr(a, name), getattr(b, name))
    for x, y in zip(compiled.swing_tip_motion(q, qd), python.swing_tip_motion(q, qd)):
        _assert_same(x, y)
    for mirrored in (False, True):
        a, b = compiled.poses(q, qd, mirrored), python.poses(q, qd, mirrored)
        for name in a.__dataclass_fields__:
            _assert_same(getattr(a, name), getattr(b, name))
    _assert_same(compiled.energy(q, qd), python.energy(q, qd))
    urdf = WorldView(planner.model).urdf_model
    urdf_q = np.random.default_rng(6).uniform(-2.5, 2.5, (20, urdf.nq))
    compiled, python = JointPlacements(urdf, native=True), JointPlacements(urdf, native=False)
    for x, y in zip(compiled.local(urdf_q), python.local(urdf_q)):
        _assert_same(x, y)


def test_evaluations_are_the_one_sample_functions(planner, states):
    """Each row is what the model's one-state functions give (ABA, RNEA ground reaction, swing
    tip by forward kinematics, momenta, the tip's velocity by its Jacobian)."""
    bm, evaluator = planner.model, planner.hybrid.samples
    q, qd = states
    dynamics = evaluator.dynamics(q, qd)
    height, rate = evaluator.swing_tip_motion(q, qd)
    poses = evaluator.poses(q, qd)
    for i in range(0, len(q), 7):
        qdd = planner.flow.acceleration(q[i], qd[i])
        xd = np.concatenate([np.zeros(3), qd[i]])
        p, h_origin, com = bm.momentum(q[i], xd)
        _, j2 = bm.tip_jacobians(q[i])
        _assert_same(dynamics.qdd[i], qdd)
        _assert_same(dynamics.grf[i], ground_reaction_inverse_dynamics(bm, q[i], qd[i], qdd))
        assert dynamics.swing_height[i] == pytest.approx(bm.swing_tip(q[i])[2], abs=1e-15) == height[i]
        assert rate[i] == pytest.approx(j2[2] @ xd, abs=1e-12)
        assert dynamics.yaw_momentum[i] == pytest.approx(bm.vertical_momentum_about(q[i], xd, np.zeros(3)), abs=1e-12)
        _assert_same(poses.com[i], com)
        _assert_same(poses.momentum[i], p)
        _assert_same(poses.angular_momentum[i], h_origin)
        pin.forwardKinematics(bm.single, bm.single_data, q[i])
        hands = [bm.single_data.oMi[bm.single.getJointId(name)].act(np.array([0, 0, -bm.params.arm.length]))[2]
                 for name in ("stance_side_shoulder", "swing_side_shoulder")]
        knees_up = [bm.single_data.oMi[j].translation[2] for j in range(3, bm.single.njoints)]
        assert dynamics.lowest_link[i] == min(knees_up + hands)


def test_step_figures_are_the_same_either_way(planner, default_gait):
    samples = default_gait.figures.samples
    figures = [
        step_figures(SampleEvaluator(planner.model, native=native), samples.t, samples.q, samples.qd,
                     default_gait.period, 0.0)
        for native in (True, False)
    ]
    for name in ("min_grf_z", "min_swing_height", "max_friction_ratio", "q9_min"):
        assert getattr(figures[0], name) == pytest.approx(getattr(figures[1], name), rel=1e-13)
    _assert_same(figures[0].grf, figures[1].grf)
    _assert_same(figures[0].h_vertical, figures[1].h_vertical)
    _assert_same(figures[0].grf, default_gait.figures.grf)


def test_world_pictures_are_the_world_states(planner, states):
    """Many instants in one call give each instant's world state, compiled or not, either foot."""
    q, qd = states
    compiled, python = WorldView(planner.model, native=True), WorldView(planner.model, native=False)
    for side, foot in (("right", np.array([0.9, -0.2, 0.0])), ("left", np.array([1.35, 0.2, 0.0]))):
        pictures = compiled.pictures(q, qd, side, foot)
        assert len(pictures) == len(q)
        for i in (0, 40, len(q) - 1):
            a, b = pictures.state(i), python.state(q[i], qd[i], side, foot)
            assert a.joint_names == b.joint_names
            assert a.joint_positions == b.joint_positions and a.joint_velocities == b.joint_velocities
            for name in ("pelvis_position", "pelvis_quaternion", "pelvis_linear_velocity", "pelvis_angular_velocity",
                         "stance_foot", "com", "momentum_about_foot", "momentum_about_com"):
                _assert_same(getattr(a, name), getattr(b, name))
            assert [(t.parent, t.child) for t in a.link_transforms] == [(t.parent, t.child) for t in b.link_transforms]
            for x, y in zip(a.link_transforms, b.link_transforms):
                _assert_same(x.translation, y.translation)
                _assert_same(x.quaternion, y.quaternion)


@pytest.mark.parametrize("which", ["planner", "hips"])
def test_world_efforts_are_the_joint_torques_with_their_power(which, request):
    """The joints' efforts are the model's torques mapped to the URDF's joints: none without
    torques, and with torques on the actuated coordinates (the passive ones, the stance foot's,
    have none) the same power sum(effort * rate) as the model's torque . qd, either foot; the
    power's tolerance is rounding of sums of 13 products of order 10 (1e-12)."""
    bm = request.getfixturevalue(which).model
    view = WorldView(bm)
    rng = np.random.default_rng(7)
    q, qd = rng.uniform(-1.0, 1.0, (5, bm.nq)), rng.uniform(-3.0, 3.0, (5, bm.nq))
    torque = np.zeros((5, bm.nq))
    torque[:, bm.actuated] = rng.uniform(-5.0, 5.0, (5, len(bm.actuated)))
    for side in ("right", "left"):
        assert not np.any(view.pictures(q, qd, side, np.zeros(3)).joint_efforts)
        pictures = view.pictures(q, qd, side, np.zeros(3), torque=torque)
        assert pictures.joint_efforts.shape == pictures.joint_velocities.shape
        power = np.sum(pictures.joint_efforts * pictures.joint_velocities, axis=1)
        np.testing.assert_allclose(power, np.sum(torque * qd, axis=1), rtol=0, atol=1e-12)


@pytest.mark.parametrize("native", [True, False])
def test_bad_batches_are_refused(planner, native):
    evaluator = SampleEvaluator(planner.model, native=native)
    with pytest.raises(ValueError, match="n x 9"):
        evaluator.dynamics(np.zeros((3, 8)), np.zeros((3, 8)))
    with pytest.raises(ValueError, match="n x 9"):
        evaluator.poses(np.zeros((3, 9)), np.zeros((2, 9)))
