"""Kinematics: the leg-exchange map P against forward kinematics, the boundary configurations,
the locked rotation z_d, and the URDF against the dynamics model."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from biped_gait.core.gait.configurations import GaitMode, boundary_configurations
from biped_gait.core.dynamics.hybrid import MIRROR, P_MATRIX, exchange, locked_rotation
from biped_gait.core.model.biped import BipedModel
from biped_gait.core.model.params import load_params
from biped_gait.core.model.urdf import PHYSICAL_JOINTS, make_urdf, physical_joint_positions

pytestmark = pytest.mark.core



@pytest.fixture(scope="module")
def bm() -> BipedModel:
    return BipedModel.from_params(load_params())


def _points(bm: BipedModel, q: np.ndarray) -> dict[str, np.ndarray]:
    """World positions of the feet, knees, hips, shoulders and hands, and the trunk CoM."""
    model, data = bm.single, bm.single_data
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    p = bm.params
    joint = lambda name: data.oMi[model.getJointId(name)]  # noqa: E731
    hand = lambda name: joint(name).act(np.array([0, 0, -p.arm.length]))  # noqa: E731
    pelvis = joint("stance_hip")
    points = {
        "stance_foot": np.zeros(3),
        "stance_knee": joint("stance_knee").translation,
        "stance_hip": pelvis.act(np.array([0, -p.hip_half_width, 0])),
        "swing_hip": joint("swing_hip").translation,
        "swing_knee": joint("swing_knee").translation,
        "swing_foot": data.oMf[model.getFrameId("swing_tip")].translation,
        "stance_side_shoulder": joint("stance_side_shoulder").translation,
        "swing_side_shoulder": joint("swing_side_shoulder").translation,
        "stance_side_hand": hand("stance_side_shoulder"),
        "swing_side_hand": hand("swing_side_shoulder"),
        "trunk_com": joint("torso_yaw").act(np.array([0, 0, p.trunk.com_offset])),
    }
    return {name: np.array(v, copy=True) for name, v in points.items()}  # detach from Pinocchio's data


def _random_double_support(rng) -> np.ndarray:
    """A configuration with the same joint layout as a double support but random angles."""
    return rng.uniform(-0.6, 0.6, 9)


@pytest.mark.parametrize("seed", range(8))
def test_exchange_map_is_the_mirror_image(bm, seed):
    """FK(P q) = mirror(FK(q)) with legs and arms exchanged, translated to leg 2's tip."""
    q = _random_double_support(np.random.default_rng(seed))
    before, after = _points(bm, q), _points(bm, exchange(q))
    new_origin = before["swing_foot"]
    swap = {
        "stance_foot": "swing_foot",
        "stance_knee": "swing_knee",
        "stance_hip": "swing_hip",
        "swing_hip": "stance_hip",
        "swing_knee": "stance_knee",
        "swing_foot": "stance_foot",
        "stance_side_shoulder": "swing_side_shoulder",
        "swing_side_shoulder": "stance_side_shoulder",
        "stance_side_hand": "swing_side_hand",
        "swing_side_hand": "stance_side_hand",
        "trunk_com": "trunk_com",
    }
    for name, other in swap.items():
        expected = MIRROR @ (before[other] - new_origin)
        assert np.allclose(after[name], expected, atol=1e-12), name


@pytest.mark.parametrize("mode", list(GaitMode))
@pytest.mark.parametrize("theta", [0.0, 0.01, -0.03])
def test_boundary_configurations_close_under_p(bm, mode, theta):
    q0, q_t = boundary_configurations(0.45, bm.params.leg_length, math.radians(23.5), mode, theta)
    assert np.allclose(P_MATRIX @ q_t, q0, atol=1e-15)
    # Both feet on the ground, 0.40 m apart, the new one L ahead; the pelvis pitched by theta.
    assert np.allclose(bm.swing_tip(q_t), [0.45, 2 * bm.params.hip_half_width, 0.0], atol=1e-12)
    assert np.allclose(bm.swing_tip(q0), [-0.45, 2 * bm.params.hip_half_width, 0.0], atol=1e-12)
    assert q0[1] + q0[2] + q0[3] == pytest.approx(theta, abs=1e-15)


def test_locked_rotation_moves_neither_foot_nor_any_joint(bm):
    _, q_t = boundary_configurations(0.45, bm.params.leg_length, 0.4, GaitMode.NORMAL, 0.0)
    z = locked_rotation(bm, q_t)
    j1, j2 = bm.tip_jacobians(q_t)
    assert np.abs(j1 @ z).max() < 1e-14 and np.abs(j2 @ z).max() < 1e-14
    assert np.abs(z[5:]).max() == 0.0  # B_e^T z_d = 0: no actuated joint moves
    assert np.linalg.norm(z) == pytest.approx(1.0)


def test_tip_jacobians_match_finite_differences(bm):
    rng = np.random.default_rng(3)
    q, dq = rng.uniform(-0.5, 0.5, 9), rng.normal(size=9)
    _, j2 = bm.tip_jacobians(q)
    h = 1e-6
    fd = (bm.swing_tip(q + h * dq) - bm.swing_tip(q - h * dq)) / (2 * h)
    assert np.allclose(j2[:, 3:] @ dq, fd, atol=1e-8)
    assert np.allclose(j2[:, :3], np.eye(3))


def test_urdf_agrees_with_the_dynamics_model(bm):
    """Feet and hands placed by the URDF (pelvis as floating base) equal the model's."""
    urdf = pin.buildModelFromXML(make_urdf(bm.params), pin.JointModelFreeFlyer())
    data = urdf.createData()
    assert pin.computeTotalMass(urdf) == pytest.approx(52.1, abs=1e-9)
    rng = np.random.default_rng(11)
    for stance_side in ("right", "left"):
        q = rng.uniform(-0.6, 0.6, 9)
        pts = _points(bm, q)
        model, mdata = bm.single, bm.single_data
        pin.forwardKinematics(model, mdata, q)
        pelvis = mdata.oMi[model.getJointId("stance_hip")]
        angles = physical_joint_positions(q, stance_side)
        assert set(angles) == set(PHYSICAL_JOINTS)
        mirror = np.eye(3) if stance_side == "right" else MIRROR
        # The left-stance robot is the mirror of the model: mirror the pelvis pose as well.
        rot = mirror @ pelvis.rotation @ mirror
        x = np.zeros(urdf.nq)
        x[:3] = mirror @ pelvis.translation
        x[3:7] = pin.Quaternion(rot).coeffs()
        for name, value in angles.items():
            x[urdf.joints[urdf.getJointId(name)].idx_q] = value
        pin.framesForwardKinematics(urdf, data, x)
        where = lambda frame: data.oMf[urdf.getFrameId(frame)].translation  # noqa: E731
        stance, swing = stance_side, "left" if stance_side == "right" else "right"
        assert np.allclose(where(f"{stance}_foot"), mirror @ pts["stance_foot"], atol=1e-12)
        assert np.allclose(where(f"{swing}_foot"), mirror @ pts["swing_foot"], atol=1e-12)
        assert np.allclose(where(f"{stance}_hand"), mirror @ pts["stance_side_hand"], atol=1e-12)
        assert np.allclose(where(f"{swing}_hand"), mirror @ pts["swing_side_hand"], atol=1e-12)
