"""Kinematics of every shipped parameter set: the leg exchange against forward kinematics, the
boundary configurations, the locked rotation z_d, the joint table's derived maps, and the URDF
against the dynamics model."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from biped_gait.core.dynamics.hybrid import HybridStep, locked_rotation
from biped_gait.core.gait.configurations import GaitMode, boundary_configurations
from biped_gait.core.model.biped import PELVIS, BipedModel
from biped_gait.core.model.exchange import MIRROR, exchange_matrix, leg_exchange
from biped_gait.core.model.params import load_params, shipped_param_names
from biped_gait.core.model.urdf import UrdfJoints, make_urdf

pytestmark = pytest.mark.core

SETS = ("aoustin2013", "aoustin2013-table", "aoustin2013-hips")


@pytest.fixture(scope="module", params=SETS)
def bm(request) -> BipedModel:
    return BipedModel.from_params(load_params(request.param))


def _rz(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _points(bm: BipedModel, q: np.ndarray) -> dict[str, np.ndarray]:
    """World positions of the feet, knees, hips, shoulders and hands, and the trunk CoM."""
    model, data = bm.single, bm.single_data
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    p = bm.params
    joint = lambda k: data.oMi[model.getJointId(bm.names[k])]  # noqa: E731
    hand = lambda k: joint(k).act(np.array([0, 0, -p.arm.length]))  # noqa: E731
    pelvis = data.oMf[model.getFrameId(PELVIS)]
    hips = p.joints.hip_roles
    points = {
        "stance_foot": np.zeros(3),
        "stance_knee": joint(bm.index("knee")).translation,
        "stance_hip": pelvis.act(np.array([0, -p.hip_half_width, 0])),
        "swing_hip": pelvis.act(np.array([0, p.hip_half_width, 0])),
        "swing_knee": joint(bm.index("knee", "swing")).translation,
        "swing_foot": data.oMf[model.getFrameId("swing_tip")].translation,
        "stance_side_shoulder": joint(bm.index("shoulder", "stance")).translation,
        "swing_side_shoulder": joint(bm.index("shoulder", "swing")).translation,
        "stance_side_hand": hand(bm.index("shoulder", "stance")),
        "swing_side_hand": hand(bm.index("shoulder", "swing")),
        "trunk_com": joint(bm.index("torso_yaw")).act(np.array([0, 0, p.trunk.com_offset])),
    }
    assert np.allclose(joint(bm.index(hips[0], "swing")).translation, points["swing_hip"], atol=1e-14)
    return {name: np.array(v, copy=True) for name, v in points.items()}  # detach from Pinocchio's data


@pytest.mark.parametrize("seed", range(8))
def test_exchange_map_is_the_mirror_image(bm, seed):
    """FK(P q) = the mirror image of FK(q), legs and arms exchanged, translated to leg 2's tip and
    turned by the heading change about the vertical (zero for legs of pitch joints only)."""
    q = np.random.default_rng(seed).uniform(-0.6, 0.6, bm.nq)
    exchange = leg_exchange(bm)
    before, after = _points(bm, q), _points(bm, exchange.configuration(q))
    new_origin = before["swing_foot"]
    turn = _rz(exchange.heading(q))
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
        expected = turn.T @ MIRROR @ (before[other] - new_origin)
        assert np.allclose(after[name], expected, atol=1e-12), name
    if not bm.params.joints.lateral_hips:
        assert exchange.heading(q) == 0.0


def test_exchange_is_an_involution_and_maps_velocities_by_its_differential(bm):
    """P(P(q)) = q; the joint velocity of the next step, from a double-support velocity with the
    new stance tip at rest, is the derivative of P along that motion (finite differences of FK)."""
    rng = np.random.default_rng(5)
    hybrid = HybridStep(bm)
    exchange = hybrid.exchange
    for _ in range(4):
        q = rng.uniform(-0.4, 0.4, bm.nq)
        assert np.allclose(exchange.configuration(exchange.configuration(q)), q, atol=1e-13)
        impact = hybrid.impact(q)
        v = rng.normal(size=bm.nq)  # the next step's joint velocity
        xd = impact.next_step_velocity(v)
        assert np.abs(impact.j2 @ xd).max() < 1e-12  # the new stance tip at rest (and not spinning)
        assert np.allclose(exchange.velocity(q, xd), v, atol=1e-12)


def test_the_linear_exchange_is_the_papers_p():
    """The 9-DOF exchange derived from the roles is the matrix of docs/model.md section 5."""
    p = np.zeros((9, 9))
    for row, entries in enumerate([{0: -1}, {1: 1, 2: 1, 3: 1, 7: 1, 8: 1}, {8: -1}, {7: -1}, {4: -1}, {6: 1},
                                   {5: 1}, {3: -1}, {2: -1}]):
        for col, value in entries.items():
            p[row, col] = value
    for name in ("aoustin2013", "aoustin2013-table"):
        bm = BipedModel.from_params(load_params(name))
        assert np.array_equal(exchange_matrix(bm.coordinates), p)
        assert np.array_equal(leg_exchange(bm).inverse, np.linalg.inv(p))


@pytest.mark.parametrize("mode", list(GaitMode))
@pytest.mark.parametrize("theta", [0.0, 0.01, -0.03])
def test_boundary_configurations_close_under_p(bm, mode, theta):
    widths = [None] + ([0.3, 0.5] if bm.params.joints.lateral_hips else [])
    exchange = leg_exchange(bm)
    for width in widths:
        w = bm.params.hip_spacing if width is None else width
        q0, q_t = boundary_configurations(bm)(0.45, math.radians(23.5), mode, theta, width)
        assert np.allclose(exchange.configuration(q_t), q0, atol=1e-14)
        assert abs(exchange.heading(q_t)) < 1e-14  # a straight gait
        # Both feet on the ground, w apart, the new one L ahead; the pelvis level, pitched by theta.
        assert np.allclose(bm.swing_tip(q_t), [0.45, w, 0.0], atol=1e-12)
        assert np.allclose(bm.swing_tip(q0), [-0.45, w, 0.0], atol=1e-12)
        pin.framesForwardKinematics(bm.single, bm.single_data, q_t)
        pelvis = bm.single_data.oMf[bm.single.getFrameId(PELVIS)].rotation
        c, s = math.cos(theta), math.sin(theta)
        assert np.allclose(pelvis, [[c, 0, s], [0, 1, 0], [-s, 0, c]], atol=1e-12)
        if width is None:
            assert q0[1] + q0[2] + q0[bm.index("hip_pitch")] == pytest.approx(theta, abs=1e-15)


def test_locked_rotation_moves_neither_foot_nor_any_joint(bm):
    _, q_t = boundary_configurations(bm)(0.45, 0.4, GaitMode.NORMAL, 0.0)
    hybrid = HybridStep(bm)
    impact = hybrid.impact(q_t)
    z = locked_rotation(bm, q_t)
    assert np.abs(impact.j1 @ z).max() < 1e-14 and np.abs(impact.j2 @ z).max() < 1e-14  # the feet, and their spin
    assert np.abs(z[bm.ds_actuated]).max() == 0.0  # B_e^T z_d = 0: no actuated joint moves
    assert np.linalg.norm(z) == pytest.approx(1.0)


def test_tip_jacobians_match_finite_differences(bm):
    rng = np.random.default_rng(3)
    q, dq = rng.uniform(-0.5, 0.5, bm.nq), rng.normal(size=bm.nq)
    _, j2 = bm.tip_jacobians(q)
    h = 1e-6
    fd = (bm.swing_tip(q + h * dq) - bm.swing_tip(q - h * dq)) / (2 * h)
    assert np.allclose(j2 @ bm.embed(dq), fd, atol=1e-8)
    assert np.allclose(j2[:, :3], np.eye(3))


def test_derived_layout_of_the_hips_model():
    """The joint table decides the coordinates, the impulses' size and the messages' joint lists."""
    bm = BipedModel.from_params(load_params("aoustin2013-hips"))
    assert bm.nq == 13 and bm.double_support.nv == 17 and len(bm.actuated) == 11
    assert bm.names[:3] == ("stance_ankle_roll", "stance_ankle_pitch", "stance_knee")
    assert bm.names[-4:] == ("swing_hip_yaw", "swing_hip_roll", "swing_hip_pitch", "swing_knee")
    assert UrdfJoints(bm.params.joints, bm.coordinates).names[:4] == (
        "right_hip_yaw", "right_hip_roll", "right_hip_pitch", "right_knee")
    assert pin.computeTotalMass(bm.single) == pytest.approx(52.1, abs=1e-12)  # the hips' joints add no mass
    assert set(shipped_param_names()) >= set(SETS)


def test_urdf_agrees_with_the_dynamics_model(bm):
    """Feet and hands placed by the URDF (pelvis as floating base) equal the model's."""
    urdf = pin.buildModelFromXML(make_urdf(bm.params), pin.JointModelFreeFlyer())
    data = urdf.createData()
    assert pin.computeTotalMass(urdf) == pytest.approx(52.1, abs=1e-9)
    joints = UrdfJoints(bm.params.joints, bm.coordinates)
    assert len(joints.names) == urdf.nq - 7
    rng = np.random.default_rng(11)
    for stance_side in ("right", "left"):
        q = rng.uniform(-0.6, 0.6, bm.nq)
        pts = _points(bm, q)
        model, mdata = bm.single, bm.single_data
        pin.framesForwardKinematics(model, mdata, q)
        pelvis = mdata.oMf[model.getFrameId(PELVIS)]
        angles = joints.positions(q, stance_side)
        assert set(angles) == set(joints.names)
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
