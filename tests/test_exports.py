"""The exported robot files (MJCF and URDF) load in MuJoCo and in Pinocchio, and their dynamics are
the planner's: mass matrices and gravity/Coriolis terms against the project's Pinocchio models,
the plan checked by MuJoCo (``biped-gait check-mujoco``)."""

from __future__ import annotations

import math
import re
import subprocess
import sys

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from biped_gait.core.dynamics.hybrid import HybridStep
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.model.biped import BipedModel
from biped_gait.core.model.exported import EPSILON_INERTIA, EPSILON_MASS
from biped_gait.core.model.mjcf import make_mjcf
from biped_gait.core.model.params import load_params
from biped_gait.core.model.urdf import make_urdf
from biped_gait.studies.mujoco_check import check_gait

pytestmark = pytest.mark.core

SETS = ("aoustin2013", "aoustin2013-table", "aoustin2013-hips")
EPSILON_BOUND = 1e-8
"""What the exports' epsilon inertias may change (kg m^2 in the mass matrix, N m in the bias
terms): EPSILON_MASS at the pelvis (lever arms under 2 m, speeds under 10 rad/s) and a few
EPSILON_INERTIA, with a margin of ten."""
ROUNDING = 1e-11  # the two engines' rounding on entries up to 60 kg m^2 and 800 N m


@pytest.fixture(scope="module", params=SETS)
def bm(request) -> BipedModel:
    return BipedModel.from_params(load_params(request.param))


def _mass(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    out = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, out)
    return out


def _symmetric(m: np.ndarray) -> np.ndarray:
    return np.triu(m) + np.triu(m, 1).T


def _states(n: int, count: int = 6, seed: int = 3):
    rng = np.random.default_rng(seed)
    return [(rng.uniform(-0.8, 0.8, n), rng.uniform(-4.0, 4.0, n)) for _ in range(count)]


def test_the_bound_covers_the_epsilons():
    assert EPSILON_MASS * 2.0 ** 2 * 10 + 8 * EPSILON_INERTIA < EPSILON_BOUND


@pytest.mark.parametrize("kind", ["stance", "extended"])
def test_mjcf_trees_have_the_planners_dynamics(bm, kind):
    """The stance tree's qpos is q and the extended tree's is X: MuJoCo's M and bias terms (gravity,
    Coriolis) are the planner's within the epsilons' bound, and the tips' Jacobians its J1, J2."""
    model = mujoco.MjModel.from_xml_string(make_mjcf(bm.params, kind))
    data = mujoco.MjData(model)
    pinocchio = bm.single if kind == "stance" else bm.double_support
    pdata = pinocchio.createData()
    assert [model.joint(i).name for i in range(model.njnt)] == list(bm.names if kind == "stance" else bm.ds_names)
    assert sum(model.body_mass) == pytest.approx(bm.total_mass, abs=2 * EPSILON_MASS)
    for q, qd in _states(bm.nq):
        x, xd = (q, qd) if kind == "stance" else (bm.ds_state(q), bm.embed(qd))
        data.qpos[:], data.qvel[:] = x, xd
        mujoco.mj_forward(model, data)
        assert np.max(np.abs(_mass(model, data) - _symmetric(pin.crba(pinocchio, pdata, x)))) < EPSILON_BOUND
        bias = pin.rnea(pinocchio, pdata, x, xd, np.zeros(len(xd)))
        assert np.max(np.abs(data.qfrc_bias - bias)) < EPSILON_BOUND
        # and not just agreement to a loose bound: the terms are large
        assert np.max(np.abs(bias)) > 10.0
        if kind == "extended":
            j1, j2 = bm.tip_jacobians(q)
            for site, expected in (("stance_tip", j1), ("swing_tip", j2)):
                jac = np.zeros((3, model.nv))
                mujoco.mj_jacSite(model, data, jac, None, model.site(site).id)
                assert np.max(np.abs(jac - expected)) < ROUNDING


def _by_name(model: pin.Model, names: list[str]) -> list[int]:
    return [model.joints[model.getJointId(n)].idx_v for n in names]


def test_urdf_loads_in_mujoco_and_pinocchio_with_the_same_dynamics(bm):
    """The URDF, fixed at the pelvis: MuJoCo's and Pinocchio's M and bias terms agree to rounding
    (the same file, the same epsilons), with the table's limits, and its comment states the
    epsilons."""
    text = make_urdf(bm.params)
    assert f"mass {EPSILON_MASS:g} kg" in text and "base_link" in re.search(r"<!--(.*?)-->", text).group(1)
    model = mujoco.MjModel.from_xml_string(text)
    data = mujoco.MjData(model)
    urdf = pin.buildModelFromXML(text)
    udata = urdf.createData()
    names = [model.joint(i).name for i in range(model.njnt)]
    assert sorted(names) == sorted(bm.params.joints.physical_names())
    order = _by_name(urdf, names)
    knee = bm.params.joints.role("knee").limits
    assert tuple(model.joint("right_knee").range) == pytest.approx((knee.lower, knee.upper))
    assert model.ngeom >= 3 * 7 + 2  # a capsule (cylinder and two spheres) per limb, a sphere per foot
    for q, qd in _states(model.nq, seed=5):
        data.qpos[:], data.qvel[:] = q, qd
        mujoco.mj_forward(model, data)
        qp, vp = np.zeros(urdf.nq), np.zeros(urdf.nv)
        qp[order], vp[order] = q, qd
        mass = _symmetric(pin.crba(urdf, udata, qp))[np.ix_(order, order)]
        assert np.max(np.abs(_mass(model, data) - mass)) < ROUNDING
        assert np.max(np.abs(data.qfrc_bias - pin.rnea(urdf, udata, qp, vp, np.zeros(urdf.nv))[order])) < ROUNDING


def test_floating_mjcf_is_the_urdf_robot_with_a_free_pelvis(bm):
    """The floating MJCF against Pinocchio's URDF with a free-flyer root: MuJoCo's free joint has
    the pelvis's linear velocity in world axes (Pinocchio's in the pelvis frame), so with
    v_mujoco = T v_pinocchio, M_pin = T^T M T and b_pin = T^T (b + M [R (w x v); 0])."""
    model = mujoco.MjModel.from_xml_string(make_mjcf(bm.params, "floating"))
    data = mujoco.MjData(model)
    urdf = pin.buildModelFromXML(make_urdf(bm.params), pin.JointModelFreeFlyer())
    udata = urdf.createData()
    names = [model.joint(i).name for i in range(1, model.njnt)]
    order = [0, 1, 2, 3, 4, 5] + _by_name(urdf, names)
    assert model.nu == len(names) and model.nv == 6 + len(names)
    rng = np.random.default_rng(7)
    for q, qd in _states(len(names), seed=9):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        rotation = pin.Quaternion(*quat).toRotationMatrix()  # (w, x, y, z)
        position, linear, angular = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        data.qpos[:] = np.concatenate([position, quat, q])
        data.qvel[:] = np.concatenate([rotation @ linear, angular, qd])
        mujoco.mj_forward(model, data)
        qp, vp = np.zeros(urdf.nq), np.zeros(urdf.nv)
        qp[:7] = np.concatenate([position, quat[1:], quat[:1]])
        vp[:6] = np.concatenate([linear, angular])
        qp[np.array(order[6:]) + 1], vp[order[6:]] = q, qd
        t = np.eye(model.nv)
        t[:3, :3] = rotation
        mass = _mass(model, data)
        shift = np.zeros(model.nv)
        shift[:3] = rotation @ np.cross(angular, linear)
        expected_mass = _symmetric(pin.crba(urdf, udata, qp))[np.ix_(order, order)]
        expected_bias = pin.rnea(urdf, udata, qp, vp, np.zeros(urdf.nv))[order]
        assert np.max(np.abs(t.T @ mass @ t - expected_mass)) < EPSILON_BOUND
        assert np.max(np.abs(t.T @ (data.qfrc_bias + mass @ shift) - expected_bias)) < EPSILON_BOUND


@pytest.mark.parametrize("params, alpha", [("aoustin2013", 23.5), ("aoustin2013-hips", 20.0)])
def test_mujoco_follows_the_plan(params, alpha):
    """The planned ballistic step integrated by MuJoCo (RK4, 1e-4 s) from the export stays within
    1e-8 rad of the plan, its swing tip lands where the plan's does, and the impact equations with
    MuJoCo's matrices give the plan's next-step velocity."""
    planner = GaitPlanner(params)
    gait = planner.plan(GaitRequest(0.45, 0.45, math.radians(alpha), "normal"))
    check = check_gait(gait, HybridStep(planner.model))
    assert check.max_joint_error < 1e-8
    assert check.swing_tip_error < 1e-9
    assert check.energy_drift_mujoco < 1e-9
    assert check.impact_velocity_error < 1e-8 and check.impact_equation_residual < 1e-8
    # a coarser MuJoCo step is measurably worse: the figure measures the integration
    coarse = check_gait(gait, HybridStep(planner.model), timestep=5e-3)
    assert coarse.max_joint_error > 10 * check.max_joint_error


def test_cli_writes_an_mjcf_mujoco_loads(tmp_path):
    out = tmp_path / "biped.xml"
    proc = subprocess.run([sys.executable, "-m", "biped_gait.cli", "mjcf", "--params", "aoustin2013-hips",
                           "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.nu == 11 and model.nv == 17
    bad = subprocess.run([sys.executable, "-m", "biped_gait.cli", "mjcf", "--kind", "nope"], capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1


def test_check_mujoco_command():
    proc = subprocess.run([sys.executable, "-m", "biped_gait.cli", "check-mujoco"], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "agrees: max joint error < 1e-08 rad" in proc.stdout
