"""The plan checked by a second engine (``biped-gait check-mujoco``, docs/model.md section 9.2):
the planned ballistic step integrated by MuJoCo from the MJCF export, and the double support's
impact equations written with MuJoCo's matrices.

- **The ballistic step**: the ``stance`` tree (``core.model.mjcf``; joints = the model's q) from the
  plan's start (q(0), qd^a) with MuJoCo's RK4 at a step of T / N (N a multiple of the plan's
  sample intervals, so that MuJoCo's states fall on the plan's samples; joint ranges not enforced,
  as the planner does not: the stance knee overextends by a fraction of a degree). Reported: the
  largest joint error (rad) and joint-rate error (rad/s) over the plan's samples, the swing tip at
  T against the plan's (m, MuJoCo's site against Pinocchio's frame), and the energy drift over
  the step in MuJoCo and in the plan (relative).
- **The impact**: D_e, J1 and J2 at the plan's touchdown configuration from the ``extended`` tree
  (MuJoCo's ``mj_fullM`` and ``mj_jacSite``; the feet's spin rows of a model with hip roll and yaw
  joints are the planner's, MuJoCo's sites having no such row), then eqs. (6)-(10) run forward with
  the plan's joint impulses (three impacts, ``hybrid.impact_with``) and compared with the plan's
  Xd^a, and the residual of all the equations at the plan's solution.

The differences include the exports' epsilon inertias (``core.model.exported``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import mujoco
import numpy as np

from ..core.dynamics.hybrid import HybridStep, impact_with
from ..core.dynamics.impulses import ImpactProblem
from ..core.gait.gait import Gait
from ..core.model.biped import STANCE_TIP, SWING_TIP
from ..core.model.mjcf import CHECK_TIMESTEP, make_mjcf
from ..core.model.params import BipedParams


@dataclass(frozen=True)
class MujocoCheck:
    """What ``check_gait`` found (units in the names' docstrings of the module)."""

    params: str
    timestep: float  # s, MuJoCo's RK4 step
    max_joint_error: float  # rad, over the plan's samples
    max_rate_error: float  # rad/s
    swing_tip_plan: tuple[float, float, float]  # m, at T
    swing_tip_error: float  # m, MuJoCo's at T against the plan's
    energy_drift_mujoco: float  # max |E / E(0) - 1| over the samples
    energy_drift_plan: float
    impact_velocity_error: float  # max |Xd^a (MuJoCo's matrices, the plan's impulses) - the plan's| (m/s, rad/s)
    impact_equation_residual: float  # max |A x - b| of eqs. (6)-(10), MuJoCo's matrices, the plan's solution

    def lines(self) -> list[str]:
        """The check as printed by ``biped-gait check-mujoco``."""
        x, y, z = self.swing_tip_plan
        return [
            f"MuJoCo {mujoco.__version__}, RK4 at {self.timestep:.3g} s, parameter set {self.params}",
            f"ballistic step: max joint error {self.max_joint_error:.2e} rad, max joint-rate error "
            f"{self.max_rate_error:.2e} rad/s over the plan's samples",
            f"swing tip at T: plan ({x:.6f}, {y:.6f}, {z:.2e}) m, MuJoCo off by {self.swing_tip_error:.2e} m",
            f"energy drift over the step: MuJoCo {self.energy_drift_mujoco:.2e}, plan {self.energy_drift_plan:.2e}",
            f"impact equations with MuJoCo's D_e, J1, J2: next-step velocity off by {self.impact_velocity_error:.2e}, "
            f"residual {self.impact_equation_residual:.2e}",
        ]

    def to_dict(self) -> dict:
        return asdict(self)


def _model(params: BipedParams, kind: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_string(make_mjcf(params, kind))
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    return model, mujoco.MjData(model)


def integrate_step(params: BipedParams, q0: np.ndarray, qd0: np.ndarray, times: np.ndarray,
                   timestep: float = CHECK_TIMESTEP) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """The ballistic step from (``q0``, ``qd0``) integrated by MuJoCo (RK4) on the ``stance`` tree,
    sampled at ``times`` (s, evenly spaced from 0): q and qd at each (rows), the energy (J) at each,
    the swing tip's position at the last (m), and the step used (s: at most ``timestep``, a whole
    number of steps between samples)."""
    model, data = _model(params, "stance")
    interval = float(times[1] - times[0])
    per_sample = max(1, math.ceil(interval / timestep - 1e-9))
    model.opt.timestep = interval / per_sample
    data.qpos[:], data.qvel[:] = q0, qd0
    q, qd, energy = np.empty((len(times), model.nq)), np.empty((len(times), model.nv)), np.empty(len(times))
    for k in range(len(times)):
        if k:
            mujoco.mj_step(model, data, nstep=per_sample)
        mujoco.mj_forward(model, data)
        q[k], qd[k], energy[k] = data.qpos, data.qvel, data.energy.sum()
    return q, qd, energy, data.site(SWING_TIP).xpos.copy(), model.opt.timestep


def impact_check(gait: Gait, hybrid: HybridStep) -> tuple[float, float]:
    """The impact equations at the plan's touchdown with MuJoCo's D_e, J1, J2 (module docstring):
    the next-step velocity's largest difference from the plan's Xd^a, and the equations' residual."""
    params, q_t = hybrid.bm.params, gait.step.q_target
    model, data = _model(params, "extended")
    data.qpos[:] = hybrid.bm.ds_state(q_t)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    impact = hybrid.impact(q_t)
    j1, j2 = impact.j1.copy(), impact.j2.copy()
    for rows, site in ((j1, STANCE_TIP), (j2, SWING_TIP)):
        mujoco.mj_jacSite(model, data, rows[:3], None, model.site(site).id)
    solution = gait.double_support.impulses
    lay = impact.layout
    xd_b, xd_a = hybrid.bm.embed(gait.step.qd_b), gait.double_support.xd_a
    xd_minus = impact_with(mass, j1, xd_b, solution.i_minus, lay.joints, at_rest=False)
    xd_plus = impact_with(mass, j2, xd_minus, np.zeros(lay.na), lay.joints, at_rest=True)
    after = impact_with(mass, j2, xd_plus, solution.i_plus, lay.joints, at_rest=True)
    a, b = ImpactProblem(mass, j1, j2, xd_b, xd_a, impact.locked_rotation, lay).equations()
    return float(np.max(np.abs(after - xd_a))), float(np.max(np.abs(a @ solution.x - b)))


def check_gait(gait: Gait, hybrid: HybridStep, timestep: float = CHECK_TIMESTEP) -> MujocoCheck:
    """The plan ``gait`` (with its samples) against MuJoCo; ``hybrid`` of its parameter set."""
    traj = gait.figures.samples
    if traj is None:
        raise ValueError("the check needs the plan's samples")
    params = hybrid.bm.params
    q, qd, energy, tip, used = integrate_step(params, traj.q[0], traj.qd[0], traj.t, timestep)
    plan_energy = hybrid.samples.energy(traj.q, traj.qd)
    plan_tip = hybrid.bm.swing_tip(traj.q[-1])
    velocity_error, residual = impact_check(gait, hybrid)
    return MujocoCheck(
        params=params.name, timestep=used,
        max_joint_error=float(np.max(np.abs(q - traj.q))), max_rate_error=float(np.max(np.abs(qd - traj.qd))),
        swing_tip_plan=tuple(float(v) for v in plan_tip), swing_tip_error=float(np.max(np.abs(tip - plan_tip))),
        energy_drift_mujoco=float(np.max(np.abs(energy / energy[0] - 1))),
        energy_drift_plan=float(np.max(np.abs(plan_energy / plan_energy[0] - 1))),
        impact_velocity_error=velocity_error, impact_equation_residual=residual,
    )
